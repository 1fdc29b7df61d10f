"""Views (phases 4 and 8): an agent as its strategy sees it, and as a snapshot records it.

:func:`robot_view` is the :class:`~mresim_phys.strategies.base.RobotView` a strategy
decides from (its robot's knowledge, read-only, never the truth); :func:`agent_snapshot`
is one agent in a :class:`~mresim_phys.snapshot.Snapshot` (views of the live grids, for
renderers and the run log). The simulation (``sim.py``) builds both every step.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from mresim_phys.agents import Agent, Robot
from mresim_phys.build import Setup
from mresim_phys.features import FEATURES
from mresim_phys.knowledge.activity import with_health
from mresim_phys.knowledge.teammates import presumed_lost, with_lost
from mresim_phys.snapshot import AgentSnapshot, bool_view, points_or_none, read_only
from mresim_phys.strategies import RobotView
from mresim_phys.strategies.base import given_up_of
from mresim_phys.strategies.relax import escape_clearance


def robot_view(
    robot: Robot,
    step: int,
    base_position: tuple[float, float],
    presume_lost_after: int,
    team_order: tuple[str, ...],
    vary_with_seed: bool,
    free_area: int,
) -> RobotView:
    """``robot``'s knowledge at ``step``, read-only, as its strategy may see it."""
    belief = robot.belief.view()
    belief.flags.writeable = False
    believed = robot.believed  # its pose as it believes it (localization/feature.py)
    return RobotView(
        step=step,
        name=robot.name,
        position=(believed[0], believed[1]),
        heading=believed[2],
        belief=belief,
        radius=robot.radius,
        clearance=clearance_of(robot),
        speed=robot.speed,
        sensor_range=robot.laser.range,
        role=robot.role,
        base_position=base_position,
        teammates=dict(robot.teammates),
        rng=robot.rng,
        bumped=robot.status == "error",
        reached_goal=robot.reached_goal,
        planner=robot.planner,
        comm_range=robot.comm_range,
        links=robot.links,
        base_contact=robot.last_base_contact,
        team_order=team_order,
        vary_with_seed=vary_with_seed,
        free_area=free_area,
        features=FEATURES.values(
            with_lost(robot.features, presumed_lost(robot.teammates, step, presume_lost_after))
        ),
        parent=robot.parent,
        children=robot.children,
        hops=robot.hops,
        escaping=robot.escape_from is not None,
        safe=read_only(robot.safe),
    )


def clearance_of(robot: Robot) -> float:
    """What its planner keeps from known walls: radius + wall margin, and wider while it
    escapes a collision that taught it nothing (``relax.escape_clearance``)."""
    clearance = robot.radius + robot.body.wall_margin
    if robot.escape_from is None:
        return clearance
    return escape_clearance(robot.belief, robot.believed_position, robot.radius, clearance)


def agent_snapshot(
    agent: Agent, lost: frozenset[str] = frozenset(), health: tuple[str, str | None] = ("", None)
) -> AgentSnapshot:
    """One agent as a snapshot (grids as read-only views); ``lost``: the teammates it
    presumes lost; ``health``: its activity this step and the reason of a state change
    this step (``knowledge.health.HealthWatch.view``).

    A strategy exposes extra views through its decision's ``info``: ``skeleton``
    (a bool grid, read-only), ``rendezvous`` (the agreed meeting points), ``rv_candidates``
    (potential ones) and ``rv_through_walls`` (those linked through walls), each (k, 2)
    float points, are passed on to renderers and the run log; ``parent`` (a robot's name,
    'base' or None) replaces the scenario's parent in the snapshot (the ``hierarchy``
    layer) when a strategy such as ``role_switch`` changes the hierarchy.
    """
    robot = agent if isinstance(agent, Robot) else None
    info = robot.decision.info if robot is not None and robot.decision is not None else {}
    return AgentSnapshot(
        name=agent.name,
        kind="robot" if robot else "base",
        position=agent.position,
        heading=robot.heading if robot else 0.0,
        radius=robot.radius if robot else 0.0,
        state=agent.state if robot else "base",
        role=agent.role,
        comm_range=agent.comm_range,
        belief=read_only(agent.belief),
        safe=read_only(agent.safe),
        path=robot.path.copy() if robot else np.zeros((0, 2)),
        goal=robot.goal if robot else None,
        distance=robot.distance if robot else 0.0,
        skeleton=bool_view(info.get("skeleton")),
        given_up=bool_view(given_up_of(robot.strategy)) if robot else None,
        rendezvous=points_or_none(info.get("rendezvous")),
        rv_candidates=points_or_none(info.get("rv_candidates")),
        rv_through_walls=points_or_none(info.get("rv_through_walls")),
        base_contact=agent.last_base_contact,
        features=FEATURES.recorded_values(
            with_health(
                with_lost(robot.features if robot else {}, lost if agent.alive else frozenset()),
                *health,
            )
        ),
        parent=info.get("parent", agent.parent),  # a strategy that changes the hierarchy
    )


def static_fields(
    setup: Setup, dt: float | None, hazards: NDArray[np.float32] | None
) -> dict[str, Any]:
    """The snapshot fields that never change during a run: the map's resolution and the
    scenario's dt, the belief rule, terrain, ground classes, prior map, hazard zones and
    what the explorable area was computed from."""
    return {
        "resolution": setup.resolution,
        "dt": dt,
        "latest": setup.rules.latest,
        "terrain": None if setup.terrain is None else read_only(setup.terrain),
        "ground": setup.ground,
        "prior": setup.prior,
        "hazards": hazards,
        "sights": tuple(setup.explorable.robots),
    }
