"""Motion (phase 5): one robot's step along its path (paper, Algorithms 1 and 2).

The decide phase (``sim.py``) replans a robot whose replan is due
(:func:`wants_plan`; a strategy may also ask for one after its robot was in
contact, :class:`~mresim_phys.strategies.base.ReplansOnContact`). Then, while the
robot has moved less than its speed this step, it takes the next path point,
replanning through its strategy when the
path has run out mid-step (the original's ``takeStep``). Each move is checked
with a swept circle of the robot's radius against the true walls. A valid move
is made and (by default) followed by a scan (at the end of its path a robot
turns in place to face what its strategy asked it to look at, then scans); an
invalid one sets the robot's error flag, marks what it bumped into in its own
map, and ends its motion for this step. The last partial move of a step is
scaled down to the remaining budget, as in the original.

Terrain (``terrain:``): a step's distance budget is ``speed * factor`` of the cell under
the robot at the start of the step (the truth, ``world/terrain.py``; 1 without terrain),
whatever ground the step then crosses; with ground classes (``ground:``) times the robot's
own factor of the class of that cell. A move that would take the robot's centre into a
cell of a class it cannot cross is refused (:func:`stop_at_ground`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache
from typing import cast

import numpy as np
from numba import njit

from mresim_phys.agents import Robot
from mresim_phys.ground.feature import GROUND
from mresim_phys.ground.grid import ClassGrid
from mresim_phys.knowledge.mapping import mark_bump
from mresim_phys.knowledge.teammates import PAYLOAD
from mresim_phys.localization.faults import frozen
from mresim_phys.localization.feature import LOCALIZATION
from mresim_phys.planning.fields import clearance_kernel
from mresim_phys.strategies.base import ReplansOnContact, ReplansWhen
from mresim_phys.types import OCCUPIED, FloatArray, IntArray
from mresim_phys.world.space import World
from mresim_phys.world.terrain import TerrainGrid, factor_at

EPS = 1e-9
MID_STEP_REPLANS = 1  # plans a robot may make on reaching its goal within one step


@dataclass(frozen=True)
class MoveRules:
    """How robots move and when they scan."""

    scan_every_point: bool
    shape_filter_of: Callable[[Robot], tuple[int, int, int]]
    terrain: TerrainGrid | None = None  # true speed factors (world/terrain.py); None: none
    ground: ClassGrid | None = None  # true ground classes (ground/grid.py); None: none


def wants_plan(robot: Robot, step: int, interval: int) -> bool:
    """Replan after an error, after reaching the goal, when the interval has passed, when
    its strategy asks for it now (:class:`~mresim_phys.strategies.base.ReplansWhen`), or
    when the robot was linked at the last exchange and its strategy asks for it."""
    due = robot.status == "error" or robot.reached_goal or step - robot.last_plan_step >= interval
    strategy: object = robot.strategy  # the protocols are optional, not part of Strategy
    if due or (
        implements(type(strategy), ReplansWhen)
        and cast(ReplansWhen, strategy).replan_now(step, robot.believed_position, robot.links)
    ):
        return True
    return (
        len(robot.links) > 0
        and implements(type(strategy), ReplansOnContact)
        and cast(ReplansOnContact, strategy).replan_on_contact(robot.belief)
    )


_IMPLEMENTS: dict[tuple[type, type], bool] = {}


def implements(kind: type, protocol: type) -> bool:
    """Whether instances of ``kind`` have the methods of the runtime-checkable ``protocol``,
    found once per class (``isinstance`` against a protocol looks the methods up at every
    call: ~5 us, twice per robot and step)."""
    known = _IMPLEMENTS.get((kind, protocol))
    if known is None:
        known = _IMPLEMENTS[kind, protocol] = issubclass(kind, protocol)
    return known


def replans_on_the_way(robot: Robot) -> bool:
    """Whether the robot's path ends within this step's move, so it will likely replan
    on the way (a hint for scheduling threads, never for what the robot does)."""
    path = robot.path
    if len(path) == 0:
        return True
    if len(path) > robot.speed + 2:  # grid paths: legs of a cell or more; enough for a hint
        return False
    legs = np.diff(np.vstack((robot.position, path)), axis=0)
    return bool(np.hypot(legs[:, 0], legs[:, 1]).sum() <= robot.speed)


def take_step(
    robot: Robot,
    world: World,
    rules: MoveRules,
    given: bool,
    replan: Callable[[Robot], None],
    sense: Callable[[Robot], None],
    settle: Callable[[], None] = lambda: None,
) -> None:
    """Move ``robot`` up to its speed along its path, sensing after each path point.

    A robot that reaches its goal with distance left to go this step asks its strategy
    once more and goes on (once a step: a second goal reached waits for the next step),
    unless its strategy sends a payload (a protocol of one decision per exchange) or
    decides once per exchange by design (``ONE_DECISION_PER_STEP``, e.g. a chain's robots,
    whose decisions read where their parents were at the last exchange);
    ``given``: its path this step is a caller's decision, never replaced mid-step.
    ``sense`` may hold its scans back (``knowledge.scanfold.ScanQueue``) until ``settle``,
    which is called before anything here reads or writes the robot's map (a replan, a bump)
    and at the end.
    """
    budget = robot.speed * factor_at(rules.terrain, robot.position)
    access = GROUND.state_of(robot.features)
    if access is not None and rules.ground is not None:  # its own factor of the ground class
        budget *= access.factor_at(rules.ground, robot.position)
    moved = False
    # a strategy that talks through its payload (rendezvous, role swaps) runs a protocol of
    # one decision per exchange: it is not asked again within the step
    once = given or PAYLOAD.key in robot.features or one_decision_per_step(robot)
    replans = 0 if once else MID_STEP_REPLANS
    while budget > EPS:
        if len(robot.path) == 0:
            if replans == 0 or not robot.reached_goal:
                break
            settle()
            replan(robot)
            replans -= 1
            continue
        used = move_towards(robot, world, rules, budget, settle)
        if used is None:
            break
        budget -= used
        moved = True
        if rules.scan_every_point or robot.reached_goal:
            look_at_goal(robot)
            sense(robot)
    if moved and not rules.scan_every_point:
        sense(robot)
    settle()


def one_decision_per_step(robot: Robot) -> bool:
    """Whether the robot's strategy decides once a step by design (its class says so)."""
    return bool(getattr(robot.strategy, "ONE_DECISION_PER_STEP", False))


def move_towards(
    robot: Robot,
    world: World,
    rules: MoveRules,
    budget: float,
    settle: Callable[[], None] = lambda: None,
) -> float | None:
    """Move toward the next path point by at most ``budget``; None if a wall is in the way
    (its map, ``settle``d first, then marks the bump). A robot with localisation drives
    from its believed pose and its body ends where the odometry's noise takes it
    (``localization/feature.py``): the true end is what the walls check."""
    target = (float(robot.path[0, 0]), float(robot.path[0, 1]))
    loc = LOCALIZATION.state_of(robot.features)
    x, y = robot.position if loc is None else loc.believed[:2]
    gap = math.hypot(target[0] - x, target[1] - y)
    if gap <= EPS:
        pop_point(robot)
        return 0.0
    share = min(1.0, budget / gap)
    end = (x + share * (target[0] - x), y + share * (target[1] - y))
    if loc is None:
        true_end, leg = end, None
    else:
        leg = loc.leg(end)
        pose = loc.drive(*leg)
        true_end = (pose[0], pose[1])
    hit = world.blocked(robot.position, true_end, robot.radius, rules.shape_filter_of(robot))
    if hit is not None:
        settle()
        stop_with_error(robot, hit.point if loc is None else loc.to_believed(hit.point))
        return None
    access = GROUND.state_of(robot.features)
    if access is not None and access.enters_barred(robot.position, true_end):
        stop_at_ground(robot)
        return None
    robot.advance_to(true_end)
    if loc is not None and leg is not None:
        robot.heading = pose[2]
        loc.arrive(*leg, pose, frozen(robot.features))
    robot.status = "active"
    if share >= 1.0:
        pop_point(robot)
    return share * gap


def look_at_goal(robot: Robot) -> None:
    """At the end of a path, turn in place to face the decision's ``look_at`` point."""
    look = robot.decision.look_at if robot.decision is not None else None
    if robot.reached_goal and look is not None:
        x, y, _ = robot.believed
        dx, dy = look[0] - x, look[1] - y
        if math.hypot(dx, dy) > EPS:
            loc = LOCALIZATION.state_of(robot.features)
            heading = math.atan2(dy, dx)
            robot.heading = heading if loc is None else loc.turn(heading, frozen(robot.features))


def pop_point(robot: Robot) -> None:
    """Drop the path point just reached; note when that was the goal."""
    robot.path = robot.path[1:]
    if len(robot.path) == 0:
        robot.reached_goal = True


def stop_with_error(robot: Robot, contact: tuple[float, float]) -> None:
    """The move was invalid: error flag, forget the path, remember the obstacle (``contact``
    where the robot believes it: its map's frame); if its map held that obstacle already,
    the robot plans wide of corners until it has moved away (``strategies/relax.py``)."""
    x, y, heading = robot.believed
    direction = np.array([math.cos(heading), math.sin(heading)])
    dx, dy = contact[0] - x, contact[1] - y
    if math.hypot(dx, dy) > EPS:
        direction = np.array([dx, dy]) / math.hypot(dx, dy)
    if not mark_bump(robot.belief, contact, direction):
        robot.escape_from = robot.position
    robot.status = "error"
    robot.path = robot.path[:0]
    robot.reached_goal = False


def stop_at_ground(robot: Robot) -> None:
    """The move would take the robot into ground it cannot cross (``ground/``): it stops
    with its error flag set and its path dropped; its map marks nothing (not a wall)."""
    robot.status = "error"
    robot.path = robot.path[:0]
    robot.reached_goal = False


def path_blocked(belief: np.ndarray, path: np.ndarray, radius: float, lookahead: float) -> bool:
    """Whether the robot's map now holds an obstacle closer than ``radius`` (its body) to
    one of the path's points (after the first, where the robot stands) in its first
    ``lookahead`` cells: the body could not pass there ('latest' beliefs: a person stepped
    into the way, a door closed; a prior map: rubble the plan did not show). A wall seen
    within the planner's wall margin but clear of the body does not block, as it does not
    stop the robot's motion. A point whose cells leave the map blocks too."""
    if len(path) < 2:
        return False
    return _path_blocked(belief, path, clearance_offsets(float(radius)), float(lookahead))


@lru_cache(maxsize=32)
def clearance_offsets(clearance: float) -> IntArray:
    """``(k, 2)`` (dr, dc) of the cells :func:`~mresim_phys.planning.fields.clearance_kernel`
    holds, relative to its centre."""
    kernel = clearance_kernel(clearance)
    offsets: IntArray = np.argwhere(kernel) - kernel.shape[0] // 2
    return offsets


@njit(cache=True, nogil=True)
def _path_blocked(
    belief: np.ndarray, path: FloatArray, offsets: IntArray, lookahead: float
) -> bool:
    """The kernel of :func:`path_blocked`: walk the path's points within ``lookahead``."""
    rows, cols = belief.shape
    travelled = 0.0
    for i in range(1, len(path)):
        travelled += np.hypot(path[i, 0] - path[i - 1, 0], path[i, 1] - path[i - 1, 1])
        if travelled > lookahead:
            return False
        col, row = math.floor(path[i, 0]), math.floor(path[i, 1])
        for k in range(len(offsets)):
            r, c = row + offsets[k, 0], col + offsets[k, 1]
            if r < 0 or r >= rows or c < 0 or c >= cols or belief[r, c] == OCCUPIED:
                return True
    return False
