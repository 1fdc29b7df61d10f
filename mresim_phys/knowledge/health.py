"""Run health (phase 7, measure): how each robot spent the run, and why its state changed.

At the end of every step :class:`HealthWatch` reads each robot's :class:`RobotStep` (what
a snapshot holds of it: state, odometer, path, drive, pose, map) and keeps, per robot:

* its *activity* in the step (after step 0, for a robot alive with a working drive):
  ``working`` (it moved at least :data:`MOVE_EPS` cells), else ``stuck`` (it had a path
  to follow, or its last move bumped: state ``error``), else ``waiting`` (``active`` and
  holding still by its strategy's choice: its goal is where it stands, as a relay at a
  meeting point, or held still by its clock: ``clocks/``), else ``idle`` (parked, done, no
  path); ``""`` when not assessed (step 0, a failed robot, a broken drive);
* ``idle_steps``, ``stuck_steps``, ``waiting_steps`` and the longest idle stretch;
* every change of its reported state (``active``, ``done``, ``error``, ``failed``) with
  the step and the reason the run gave (:class:`StateChange`; the live reasons come from
  ``health_phase.change_reason``, a replay reads them from the run log); when it became
  ``done`` (a change to ``done`` from ``active``: not a return to ``done`` after a bump or
  a repair);
* while it is idle or done, whether its OWN map holds a frontier its body could reach
  (``knowledge/frontier_reach.py``), checked when the stretch starts and then every
  :data:`CHECK_EVERY` steps of it (a robot that works is never checked): an idle step whose
  latest check found reachable frontier cells counts in ``idle_with_frontier``.

* ``fruitless_steps``: steps it was ``working`` or ``stuck`` while ``active`` although the
  team had made no progress (neither explored nor known at base gained
  :data:`PROGRESS_GAIN` since :data:`FRUITLESS_AFTER` steps before: the stall rule's
  measure, :class:`Progress`), fed by :meth:`HealthWatch.note_progress` once the
  step's metrics are known; a working robot's activity then reads ``fruitless``. This is
  a robot that never idles and yet does nothing: it chases frontier cells its scans do
  not resolve or its body cannot reach, or shuttles with a teammate (a run that ends
  ``stalled`` with every robot working). A robot going home ``done`` is not counted.

:meth:`HealthWatch.report` adds a last check of every robot's map at the end and a warning
for every robot that idled at least :data:`WARN_AFTER` steps with reachable frontier cells
in its map, and one for every robot with at least :data:`WARN_FRUITLESS` fruitless steps.
Everything here is read from what a snapshot (and so the run log) holds, so a
replay rebuilds the same record (``output.runlog.Replay``); nothing here changes the run.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any

from mresim_phys.knowledge.frontier_reach import FrontierCheck, frontier_check
from mresim_phys.types import BeliefGrid, BoolGrid

MOVE_EPS = 0.05  # cells: a robot that moved less in a step did not move
CHECK_EVERY = 20  # steps between frontier checks of a robot that stays idle or done
WARN_AFTER = 20  # idle steps with reachable frontier cells that make a warning (in a run)
PROGRESS_GAIN = 0.001  # the smallest gain of explored or known at base that is progress
FRUITLESS_AFTER = 100  # steps without progress after which a working robot's steps are fruitless
WARN_FRUITLESS = 100  # fruitless steps that make a warning (in a run)
NOT_LOGGED = "not logged"  # a change without a reason (a log written before reasons were)
WORKING, IDLE, STUCK, WAITING = "working", "idle", "stuck", "waiting"
FRUITLESS = "fruitless"  # a working step counted fruitless: the activity pictures show
TOTALS = (  # sweep columns
    "robots_idle_with_frontier",
    "idle_robot_steps",
    "stuck_robot_steps",
    "waiting_robot_steps",
    "robots_fruitless",
    "fruitless_robot_steps",
)


@dataclass(frozen=True)
class RobotStep:
    """What the watch reads of one robot at the end of a step."""

    name: str
    state: str  # active / done / error / failed
    distance: float  # odometer, cells
    has_path: bool  # points left to follow
    can_move: bool  # alive with a working drive
    position: tuple[float, float]
    radius: float
    belief: BeliefGrid
    reason: str | None = None  # why its state changed this step (None: unknown)
    safe: BoolGrid | None = None  # its safe space: where it (or a teammate it heard) has been
    given_up: BoolGrid | None = None  # frontier cells its strategy tried in vain and gave up
    goal: tuple[float, float] | None = None  # where its latest decision sends it
    clocked: bool = False  # its clock (clocks/) kept it still this step
    barred: BoolGrid | None = None  # ground it cannot cross (ground/); None: none

    @property
    def holding(self) -> bool:
        """Whether its strategy holds it still on purpose: its goal is where it stands."""
        goal = self.goal
        x, y = self.position
        return goal is not None and (goal[0] - x) ** 2 + (goal[1] - y) ** 2 < MOVE_EPS**2


def check_of(robot: RobotStep) -> FrontierCheck:
    """The frontier check of the robot's own map, where it stands."""
    return frontier_check(
        robot.belief, robot.position, robot.radius, robot.safe, robot.given_up, robot.barred
    )


def activity_of(moved: float, has_path: bool, state: str, holding: bool = False) -> str:
    """``working``, ``stuck``, ``waiting`` or ``idle`` for a robot that could move
    (module docstring); ``holding``: its goal is where it stands.

    >>> activity_of(0.5, True, "active"), activity_of(0.0, True, "active")
    ('working', 'stuck')
    >>> activity_of(0.0, False, "error"), activity_of(0.01, False, "done")
    ('stuck', 'idle')
    >>> activity_of(0.0, False, "active", holding=True), activity_of(0.0, False, "done", True)
    ('waiting', 'idle')
    """
    if moved >= MOVE_EPS:
        return WORKING
    if has_path or state == "error":
        return STUCK
    return WAITING if holding and state == "active" else IDLE


@dataclass(frozen=True)
class StateChange:
    """A robot's reported state changed at ``step``, for ``reason``."""

    step: int
    robot: str
    old: str
    new: str
    reason: str

    def summary(self) -> dict[str, Any]:
        """JSON-ready."""
        return {"step": self.step, "from": self.old, "to": self.new, "reason": self.reason}


@dataclass
class RobotHealth:
    """One robot's counts so far and what the watch remembers of its last step."""

    idle: int = 0
    stuck: int = 0
    waiting: int = 0
    idle_with_frontier: int = 0
    first_idle_with_frontier: int | None = None
    fruitless: int = 0  # working or stuck while active, the team without progress
    first_fruitless: int | None = None
    longest_idle: int = 0
    streak: int = 0  # idle steps in a row up to now
    done_at: list[int] = field(default_factory=list)
    done: bool = False  # it declared itself done (reset when it turns active)
    state: str = "active"
    distance: float = 0.0
    activity: str = ""
    reason_now: str | None = None  # the reason of a change at the latest step
    last_check: int | None = None  # step of the latest frontier check of this stretch
    check: FrontierCheck | None = None

    def summary(self) -> dict[str, Any]:
        """JSON-ready counts (the end check and state changes are added by the report)."""
        return {
            "idle_steps": self.idle,
            "stuck_steps": self.stuck,
            "waiting_steps": self.waiting,
            "longest_idle": self.longest_idle,
            "idle_with_frontier": self.idle_with_frontier,
            "first_idle_with_frontier": self.first_idle_with_frontier,
            "fruitless_steps": self.fruitless,
            "first_fruitless": self.first_fruitless,
            "done_at": list(self.done_at),
        }


class HealthWatch:
    """Every robot's run-health record, one step at a time (module docstring)."""

    def __init__(self, names: Sequence[str], check_every: int = CHECK_EVERY) -> None:
        self.robots = {name: RobotHealth() for name in names}
        self.changes: list[StateChange] = []
        self.check_every = check_every
        self.step: int | None = None  # the latest step seen
        self.progress = Progress()

    def state_of(self, name: str) -> str:
        """The state ``name`` reported at the latest step (``active`` before any)."""
        return self.robots[name].state

    def view(self, name: str) -> tuple[str, str | None]:
        """(activity, reason of a state change at the latest step) of agent ``name``;
        ("", None) for an agent that is no robot (the base)."""
        health = self.robots.get(name)
        return ("", None) if health is None else (health.activity, health.reason_now)

    def changes_at(self, step: int) -> list[StateChange]:
        """The state changes of ``step`` (the latest ones are at the end)."""
        out = []
        for change in reversed(self.changes):
            if change.step != step:
                break
            out.append(change)
        return out[::-1]

    def update(self, step: int, robots: Sequence[RobotStep]) -> None:
        """Take the end of ``step`` (steps in order; the first one seen is not assessed)."""
        first, self.step = self.step is None, step
        for robot in robots:
            health = self.robots[robot.name]
            self.note_state(step, robot, health)
            moved = robot.distance - health.distance
            assessed = not first and robot.can_move
            activity = activity_of(moved, robot.has_path, robot.state, robot.holding)
            if robot.clocked and moved < MOVE_EPS:  # its clock, not the robot, kept it still
                activity = WAITING
            health.activity = activity if assessed else ""
            health.distance = robot.distance
            self.count(step, robot, health)

    def note_progress(self, step: int, explored: float, known_at_base: float) -> None:
        """The team's fractions at the end of ``step`` (after :meth:`update` of that
        step): count the fruitless steps of the robots that worked (module docstring)."""
        self.progress.update(step, explored, known_at_base)
        if step - self.progress.step < FRUITLESS_AFTER:
            return
        for health in self.robots.values():
            if health.state == "active" and health.activity in (WORKING, STUCK):
                health.activity = FRUITLESS if health.activity == WORKING else STUCK
                health.fruitless += 1
                if health.first_fruitless is None:
                    health.first_fruitless = step

    def note_state(self, step: int, robot: RobotStep, health: RobotHealth) -> None:
        """Record a change of the robot's reported state."""
        health.reason_now = None
        if robot.state == health.state:
            return
        reason = robot.reason or NOT_LOGGED
        self.changes.append(StateChange(step, robot.name, health.state, robot.state, reason))
        health.reason_now = reason
        if robot.state == "done" and not health.done:
            health.done_at.append(step)
        health.done = robot.state == "done" or (health.done and robot.state != "active")
        health.state = robot.state

    def count(self, step: int, robot: RobotStep, health: RobotHealth) -> None:
        """Idle and stuck counts; the frontier check of an idle or done robot when due."""
        idle = health.activity == IDLE
        if idle or robot.state == "done":
            due = health.last_check is None or step - health.last_check >= self.check_every
            if due:
                health.check = check_of(robot)
                health.last_check = step
        else:
            health.last_check, health.check = None, None
        health.stuck += health.activity == STUCK
        health.waiting += health.activity == WAITING
        health.streak = health.streak + 1 if idle else 0
        if not idle:
            return
        health.idle += 1
        health.longest_idle = max(health.longest_idle, health.streak)
        if health.check is not None and health.check.reachable > 0:
            health.idle_with_frontier += 1
            if health.first_idle_with_frontier is None:
                health.first_idle_with_frontier = step

    def report(self, robots: Sequence[RobotStep]) -> HealthReport:
        """The record at the end (``robots``: every robot at the last step)."""
        ends = {r.name: check_of(r) for r in robots}
        robots_now = {n: replace(h, done_at=list(h.done_at)) for n, h in self.robots.items()}
        return HealthReport(robots_now, ends, list(self.changes))


@dataclass
class Progress:
    """When the team last made progress: the last step at which explored or known at base
    rose by at least ``gain`` over its value at the progress before (step 0 always counts).
    Slow, steady gains add up. The stall rule (``tracking.StallWatch``) and the fruitless
    count share it."""

    gain: float = PROGRESS_GAIN
    explored: float = 0.0
    known_at_base: float = 0.0
    step: int = 0

    def update(self, step: int, explored: float, known_at_base: float) -> None:
        """Note the fractions at the end of ``step``."""
        gained = max(explored - self.explored, known_at_base - self.known_at_base)
        if step == 0 or gained >= self.gain:
            self.explored, self.known_at_base, self.step = explored, known_at_base, step


@dataclass(frozen=True)
class HealthReport:
    """The run-health record of a whole run: summary.json's ``health``."""

    robots: dict[str, RobotHealth]
    ends: dict[str, FrontierCheck]  # each robot's map at the end
    changes: list[StateChange]

    @property
    def warnings(self) -> list[str]:
        """One line per robot that idled with reachable frontier cells in its map, and
        one per robot that worked fruitlessly (module docstring)."""
        out = []
        for name, health in self.robots.items():
            if health.idle_with_frontier >= WARN_AFTER:
                out.append(
                    f"robot {name} idled {health.idle_with_frontier} steps (from step"
                    f" {health.first_idle_with_frontier}) while its map held frontier cells"
                    f" it could reach; {self.at_end(name)}"
                )
            if health.fruitless >= WARN_FRUITLESS:
                out.append(
                    f"robot {name} worked {health.fruitless} steps (from step"
                    f" {health.first_fruitless}) while the team had gained less than"
                    f" {PROGRESS_GAIN:.1%} explored or known at base in {FRUITLESS_AFTER}"
                    f" steps (chasing frontier cells it cannot resolve or reach, or"
                    f" shuttling); {self.at_end(name)}"
                )
        return out

    def at_end(self, name: str) -> str:
        """What robot ``name``'s map holds at the end, for a warning."""
        end = self.ends[name]
        rest = end.frontier - end.reachable
        return (
            f"at the end its map holds {end.frontier} frontier cells, {end.reachable} of"
            " them reachable" + (f"; {rest} unreachable: {end.reason}" if rest else "")
        )

    def totals(self) -> dict[str, int]:
        """The sweep tables' columns: robots that idled with reachable frontier cells,
        idle, stuck and waiting robot-steps, robots that worked fruitlessly and their
        fruitless robot-steps."""
        robots = list(self.robots.values())
        warned = sum(h.idle_with_frontier >= WARN_AFTER for h in robots)
        steps = (sum(h.idle for h in robots), sum(h.stuck for h in robots))
        worked = [h.fruitless for h in robots]
        fruitless = (sum(n >= WARN_FRUITLESS for n in worked), sum(worked))
        values = (warned, *steps, sum(h.waiting for h in robots), *fruitless)
        return dict(zip(TOTALS, values, strict=True))

    def summary(self) -> dict[str, Any]:
        """JSON-ready: totals, per robot counts, end check and state changes, warnings."""
        robots = {}
        for name, health in self.robots.items():
            changes = [c.summary() for c in self.changes if c.robot == name]
            end = self.ends[name].summary()
            robots[name] = {**health.summary(), "at_end": end, "state_changes": changes}
        return {**self.totals(), "robots": robots, "warnings": self.warnings}
