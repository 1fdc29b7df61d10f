"""Run health, live side (phase 7, measure): the robots' steps and their state-change reasons.

The simulation (``sim.py``) hands the run-health watch (``knowledge/health.py``) every
robot at the end of each step; when a robot's reported state differs from the one the
watch holds, :func:`change_reason` says why, from what the step left:

* ``done``, or ``active`` again after ``done``: the reason of the decision the robot took
  this step (``Decision.info["reason"]``; ``"strategy"`` when it gives none);
* ``error``: the collision (``collision at (x, y)``, where the robot stopped);
* ``failed``: the event that failed it (``fail B``, ``fail B (random)``, ...; ``"fault"``
  if no event names it); back from ``failed``: the event that repaired it (``recover B``;
  ``"repaired"``);
* out of ``error``: ``moved again`` (to ``done`` with a decision of this step: its reason).

The reasons go into the snapshot (the feature ``health``, ``knowledge/activity.py``) and
so into the run log, from which a replay reads them back; :func:`step_of` reads a replayed
robot (a snapshot's) as the live run gives it.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, Protocol

from mresim_phys.agents import Robot
from mresim_phys.broken_parts import broken_of
from mresim_phys.clocks.feature import CLOCK, ClockValue
from mresim_phys.ground.feature import GROUND
from mresim_phys.ground.grid import ClassGrid
from mresim_phys.knowledge.activity import health_of
from mresim_phys.knowledge.health import HealthWatch, RobotStep
from mresim_phys.localization.feature import LOCALIZATION
from mresim_phys.strategies.base import given_up_of
from mresim_phys.types import BeliefGrid, BoolGrid, FloatArray

PARTS = frozenset(("drive", "sensor", "radio", "degraded", "localization"))  # no state


def decision_reason(robot: Robot) -> str:
    """The reason its latest decision gives (``Decision.info["reason"]``), or ``strategy``."""
    info = robot.decision.info if robot.decision is not None else {}
    reason = info.get("reason")
    return str(reason) if reason else "strategy"


def event_naming(name: str, events: Sequence[str], verb: str) -> str | None:
    """The first of ``events`` that says ``verb`` of the whole robot ``name`` (``fail B``,
    ``fail B (random)``, not ``fail B radio``).

    >>> event_naming("B", ["fail B radio", "fail B (random)"], "fail")
    'fail B (random)'
    """
    for text in events:
        words = text.split()
        if words[:2] == [verb, name] and (len(words) == 2 or words[2] not in PARTS):
            return text
    return None


def change_reason(robot: Robot, old: str, step: int, events: Sequence[str]) -> str:
    """Why ``robot``'s state is no longer ``old`` at the end of ``step`` (module docstring)."""
    new = robot.state
    if new == "failed":
        return event_naming(robot.name, events, "fail") or "fault"
    if old == "failed":
        return event_naming(robot.name, events, "recover") or "repaired"
    if new == "error":
        x, y = robot.position
        return f"collision at ({x:.1f}, {y:.1f})"
    if old == "error" and (new == "active" or robot.last_plan_step != step):
        return "moved again"
    return decision_reason(robot)


def robot_steps(
    robots: Sequence[Robot], watch: HealthWatch, step: int, events: Sequence[str]
) -> list[RobotStep]:
    """Every robot at the end of ``step`` as the watch reads it, with the reason of a
    state change."""
    out = []
    for r in robots:
        old = watch.state_of(r.name)
        reason = None if r.state == old else change_reason(r, old, step, events)
        moving = (r.distance, len(r.path) > 0, r.can_move)
        place = (r.believed_position, r.radius, r.belief)  # its map's frame
        given_up = given_up_of(r.strategy)
        out.append(
            RobotStep(
                r.name,
                r.state,
                *moving,
                *place,
                reason=reason,
                safe=r.safe,
                given_up=given_up,
                goal=r.goal,
                clocked=held_by_clock(CLOCK.value_in(r.features), len(r.path) > 0),
                barred=barred_of(r),
            )
        )
    return out


class AgentLike(Protocol):
    """The fields of an ``AgentSnapshot`` the watch reads (a replayed robot)."""

    @property
    def name(self) -> str: ...
    @property
    def state(self) -> str: ...
    @property
    def distance(self) -> float: ...
    @property
    def path(self) -> FloatArray: ...
    @property
    def features(self) -> Mapping[str, Any]: ...
    @property
    def position(self) -> tuple[float, float]: ...
    @property
    def radius(self) -> float: ...
    @property
    def belief(self) -> BeliefGrid: ...
    @property
    def safe(self) -> BoolGrid: ...
    @property
    def given_up(self) -> BoolGrid | None: ...
    @property
    def goal(self) -> tuple[float, float] | None: ...


def step_of(agent: AgentLike, ground: ClassGrid | None = None) -> RobotStep:
    """A snapshot's robot as the watch reads it (the same values the live run gives;
    ``ground``: the run's true ground classes, None: none)."""
    crossing = GROUND.of(agent)
    barred = None if crossing is None or ground is None else crossing.barred_on(ground)
    return RobotStep(
        agent.name,
        agent.state,
        agent.distance,
        len(agent.path) > 0,
        agent.state != "failed" and "drive" not in broken_of(agent),
        believed_position(agent),
        agent.radius,
        agent.belief,
        health_of(agent).reason,
        agent.safe,
        agent.given_up,
        agent.goal,
        held_by_clock(CLOCK.of(agent), len(agent.path) > 0),
        barred,
    )


def barred_of(robot: Robot) -> BoolGrid | None:
    """The ground a live robot cannot cross (``ground/``; None: the run has none)."""
    access = GROUND.state_of(robot.features)
    return None if access is None else access.barred


def held_by_clock(clock: ClockValue | None, has_path: bool) -> bool:
    """Whether a robot's clock (``clocks/``; None: it has none) kept it still this step."""
    return clock is not None and clock.holds(has_path)


def believed_position(agent: AgentLike) -> tuple[float, float]:
    """Where a snapshot's robot believes it stands (its map's frame): the localisation
    feature's believed pose, or its position."""
    belief = LOCALIZATION.of(agent)
    return agent.position if belief is None else (belief.pose[0], belief.pose[1])
