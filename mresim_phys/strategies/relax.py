"""Relaxed clearance (phase 4, decide): a robot never quits while its body fits to a frontier.

A strategy plans on the cells at least the robot's *clearance* (body radius plus its
``wall_margin``) from every wall its map knows. On a real map that margin closes doorways
and pockets: a robot standing where it closes has no passable component and its strategy
finds nothing reachable. :func:`decide` asks the strategy as usual; when the answer is
``done`` because no frontier is reachable (``NO_FRONTIER``; a strategy's own choice, such
as the mission-complete rule, is kept), and the robot's map holds a frontier its body can
reach at the least clearance (its radius: touching walls, never through one), the strategy
is asked again with the margin relaxed in :data:`LEVELS` steps towards the radius; the
first answer that is not done is taken. ``done`` thus means: no frontier reachable under
any margin the robot may use. A done robot that its margin keeps from the way home (it
came where it stands at a relaxed clearance) heads home at the least relaxed clearance
that opens the way (:func:`_home_relaxed`), instead of parking out of the base's reach.

A collision that taught the robot's map nothing (a diagonal move past a wall corner
its map already holds) marks the robot ``escaping`` (``agents.Robot.escape_from``): until
it has moved a cell away, it plans with at least :data:`CORNER` clearance beyond its
radius, which no cell-to-cell move can cut (half a cell's diagonal), unless its own cell
is not passable at that (:func:`escape_clearance`: a start snapped to a cell nearby would
cut a corner on the way); if that boxes it in, it takes the original's random step after
a collision, on a line its body follows clear of every wall its map knows
(:func:`body_clear`), or backs off the way it came. A collision never freezes it. A path
planned at half a cell's clearance or less, the robot's own or a relaxed one, gets a stop
at the corner of every wall its diagonals pass (:func:`uncut_corners`). A path whose start
was snapped onto a passable cell away from the robot begins with a straight leg there; one
that would press the body into a wall its map knows is driven at the body's own clearance
instead (:func:`_lead_in`).

A robot left with no way out on its own map (:func:`boxed_in`: the cells its body reaches
are a pocket hardly larger than itself, while frontiers remain elsewhere) is not done: it
turns round in place and scans (:func:`look_around`), which clears walls its map holds
falsely where the rays pass; a robot truly shut in keeps looking, and counts as idle.
"""

from __future__ import annotations

import math
from dataclasses import replace
from functools import partial

import numpy as np
import shapely

from mresim_phys.knowledge.frontiers import frontiers_in
from mresim_phys.knowledge.targets import TargetFinder, target_reach
from mresim_phys.planning.fields import clearance_kernel
from mresim_phys.strategies.base import (
    HOME_TOLERANCE,
    NO_FRONTIER,
    Decision,
    RobotView,
    Strategy,
    heading_for,
    plan_context,
)
from mresim_phys.strategies.random_walk import random_step
from mresim_phys.types import OCCUPIED, BeliefGrid, FloatArray

LEVELS = (1 / 3, 2 / 3, 1.0)  # shares of the margin given up, in turn
CORNER = 0.75  # cells beyond the radius: more than half a cell's diagonal (0.707)
DEFAULT_MIN_SIZE = 3  # frontier cells of the smallest cluster, if the strategy sets none
RELAXED = "relaxed clearance"  # Decision.info["clearance_reason"] of a relaxed answer
BOXED = "boxed in: looking around"  # Decision.info["reason"] of a turn in place
HALF_CELL = 0.5  # cells: at this clearance or less a planned diagonal may touch a corner
TOUCH = 1e-6  # cells: a body this close to a wall touches it (``world.space.GRAZE``)
POCKET = 2.0  # cells beyond its radius: a reachable area under pi (r + 2)^2 is a pocket
SNAP_LEG = 1.5  # cells: a first leg longer than a diagonal move leads to a snapped start


def decide(strategy: Strategy, view: RobotView) -> Decision:
    """The strategy's decision for ``view``, relaxing its clearance before it gives up."""
    decision = strategy.decide(view)
    if decision.done and decision.info.get("reason") == NO_FRONTIER:
        decision = _relaxed(strategy, view, decision)
    elif view.escaping and len(decision.path) == 0 and not decision.done:
        decision = _random_escape(view) or decision
    if decision.done and decision.info.get("reason") == NO_FRONTIER and boxed_in(view):
        return look_around(view)
    if decision.done and len(decision.path) <= 1:
        decision = _home_relaxed(view, decision)
    return _lead_in(view, _body_path(decision, view.belief, view.clearance))


def _body_path(decision: Decision, belief: BeliefGrid, clearance: float) -> Decision:
    """``decision`` with its path's corners uncut (:func:`uncut_corners`) when it was
    planned at half a cell's clearance or less."""
    if clearance > HALF_CELL or len(decision.path) <= 1:
        return decision
    uncut = uncut_corners(decision.path, belief)
    return decision if len(uncut) == len(decision.path) else replace(decision, path=uncut)


def uncut_corners(path: FloatArray, belief: BeliefGrid) -> FloatArray:
    """``path`` with a stop added at the free corner cell of every diagonal move between
    cell centres that passes the corner of a known wall (at a clearance of half a cell or
    less, a cell beside a wall is passable and the planners' diagonal passes its corner at
    no distance: a body of any size would touch it)."""
    points = [path[0]]
    for end in path[1:]:
        start = points[-1]
        dx, dy = end[0] - start[0], end[1] - start[1]
        if abs(abs(dx) - 1.0) < 1e-9 and abs(abs(dy) - 1.0) < 1e-9:
            row, col = int(start[1]), int(start[0])
            beside = (row, int(end[0]))  # the cell the move passes on its row
            if belief[beside] == OCCUPIED:
                points.append(np.array([start[0], end[1]]))
            elif belief[int(end[1]), col] == OCCUPIED:
                points.append(np.array([end[0], start[1]]))
        points.append(end)
    return np.array(points)


def _lead_in(view: RobotView, decision: Decision) -> Decision:
    """``decision`` with a way onto its path's first point that the body can drive.

    A robot whose own cell is not passable at the clearance it planned with gets its path
    from the passable cell its start was snapped onto, up to ``planning.fields.MAX_SNAP``
    cells away, and drives the straight leg there first; that leg may press into a wall its
    map knows (ipa_office, role_based: a robot touching a wall face replanned the same leg
    into it, bumped, and stood in ``error`` for 277 steps). A first leg longer than a
    diagonal move (:data:`SNAP_LEG`) that is not :func:`body_clear` is replaced by a path
    at the body's own clearance (its radius); with none, the robot takes the escape step
    after a collision (:func:`_random_escape`)."""
    path = decision.path
    if len(path) == 0:
        return decision
    start, first = view.position, (float(path[0, 0]), float(path[0, 1]))
    if math.dist(start, first) <= SNAP_LEG or body_clear(view.belief, start, first, view.radius):
        return decision
    body = plan_context(replace(view, clearance=view.radius))
    lead = _body_path(
        replace(decision, path=body.plan_to(int(first[1]), int(first[0]))),
        view.belief, view.radius,
    ).path  # fmt: skip
    if len(lead) == 0 or not body_clear(view.belief, start, (lead[0, 0], lead[0, 1]), view.radius):
        return _random_escape(view) or decision
    return replace(decision, path=np.vstack((lead, path[1:])))


def _relaxed(strategy: Strategy, view: RobotView, decision: Decision) -> Decision:
    """Ask again at smaller clearances (down to the radius) while a frontier is in reach."""
    if view.escaping:
        return _random_escape(view) or decision
    margin = view.clearance - view.radius
    if margin <= 1e-9 or not frontier_reachable(view, view.radius, min_size(strategy)):
        return decision
    for share in LEVELS:
        clearance = view.clearance - share * margin
        relaxed = strategy.decide(replace(view, clearance=clearance))
        if not relaxed.done:
            relaxed = replace(relaxed, info={**relaxed.info, "clearance_reason": RELAXED})
            return _body_path(relaxed, view.belief, clearance)
    return decision


def _home_relaxed(view: RobotView, decision: Decision) -> Decision:
    """A done robot that its margin keeps from the way home (it came where it stands at a
    relaxed clearance) heads home at a smaller one, in :data:`LEVELS` steps; it used to
    park where it stood, out of the base's reach (ipa_office: 'mission complete' and parked
    for 256 steps with its map undelivered and frontiers in reach)."""
    if math.dist(view.position, view.base_position) <= HOME_TOLERANCE:
        return decision
    margin = view.clearance - view.radius
    info = {**decision.info, "clearance_reason": RELAXED}
    for share in LEVELS if margin > 1e-9 else ():
        clearance = view.clearance - share * margin
        context = plan_context(replace(view, clearance=clearance))
        home = heading_for(context, view.base_position, done=True, info=info)
        if len(home.path) > 1:
            return _body_path(home, view.belief, clearance)
    return decision


def _random_escape(view: RobotView) -> Decision | None:
    """The original's random step after a collision, at the robot's body clearance, on a
    line its body follows clear of every wall its map knows (:func:`body_clear`: the
    heading after a bump points into the wall, and a step that grazes on into it fails
    again, step after step); else one that backs off the way it came."""
    body = replace(view, clearance=view.radius)
    context = plan_context(body)
    fits = partial(body_clear, view.belief, radius=view.radius)
    ahead = random_step(body, context, fits)
    return ahead or random_step(body, context, fits, heading=view.heading + math.pi)


def body_clear(
    belief: BeliefGrid, start: tuple[float, float], end: tuple[float, float], radius: float
) -> bool:
    """Whether a disc of ``radius`` moving straight from ``start`` to ``end`` keeps at
    least its radius from every wall square the map holds (touching one is clear: the
    motion lets a body slide along a wall or leave it, not press into it)."""
    reach = radius + 1.0
    rows, cols = belief.shape
    r0, r1 = max(int(min(start[1], end[1]) - reach), 0), int(max(start[1], end[1]) + reach) + 1
    c0, c1 = max(int(min(start[0], end[0]) - reach), 0), int(max(start[0], end[0]) + reach) + 1
    wall_r, wall_c = np.nonzero(belief[r0 : min(r1, rows), c0 : min(c1, cols)] == OCCUPIED)
    if len(wall_r) == 0:
        return True
    squares = shapely.box(wall_c + c0, wall_r + r0, wall_c + c0 + 1, wall_r + r0 + 1)
    gaps = shapely.distance(shapely.LineString([start, end]), squares)
    return bool(gaps.min() >= radius - TOUCH)


def stands_clear(belief: BeliefGrid, position: tuple[float, float], clearance: float) -> bool:
    """Whether the robot's own cell is passable at ``clearance``: no known wall (nor the
    map's edge) closer to its centre. A start that is not gets snapped to a passable cell
    nearby, and the straight move there may cut a wall's corner."""
    row, col = int(position[1]), int(position[0])
    kernel = clearance_kernel(clearance)
    half = kernel.shape[0] // 2
    rows, cols = belief.shape
    if row - half < 0 or col - half < 0 or row + half >= rows or col + half >= cols:
        return False
    around = belief[row - half : row + half + 1, col - half : col + half + 1]
    return not bool(np.any((around == OCCUPIED) & (kernel > 0)))


def escape_clearance(
    belief: BeliefGrid, position: tuple[float, float], radius: float, nominal: float
) -> float:
    """The clearance of a robot escaping a collision: at least :data:`CORNER` beyond its
    radius where its own cell is passable at that, else its nominal clearance."""
    wide = max(nominal, radius + CORNER)
    return wide if stands_clear(belief, position, wide) else nominal


def boxed_in(view: RobotView) -> bool:
    """Whether the cells its body can reach on its map (clearance = its radius) are a
    pocket hardly larger than the body, while its map holds a frontier elsewhere: walls
    its map holds around it close every way out (false ones, often: a wall face joined
    across an alcove's mouth while it stood inside)."""
    body = plan_context(replace(view, clearance=view.radius))
    reached = int(np.count_nonzero(np.isfinite(body.field.costs)))
    if reached >= np.pi * (view.radius + POCKET) ** 2:
        return False
    return len(frontiers_in(view.belief, body.free_box, DEFAULT_MIN_SIZE)) > 0


def look_around(view: RobotView) -> Decision:
    """Turn in place to face the way behind and scan: a ray through a false wall clears it
    (``knowledge.wall_marks.clear_contradicted``), so the next plan may find the way out."""
    x, y = view.position
    behind = (x - np.cos(view.heading), y - np.sin(view.heading))
    return Decision(path=np.array([[x, y]]), goal=(x, y), look_at=behind, info={"reason": BOXED})


def frontier_reachable(view: RobotView, clearance: float, size: int = DEFAULT_MIN_SIZE) -> bool:
    """Whether the robot's map holds a frontier cluster of ``size`` cells or more that the
    robot reaches (within ``target_reach(clearance)`` cells) on the cells ``clearance`` from
    its walls."""
    context = plan_context(replace(view, clearance=clearance))
    frontiers = frontiers_in(view.belief, context.free_box, size)
    if len(frontiers) == 0:
        return False
    finder = TargetFinder.of(frontiers, context.passable, target_reach(clearance))
    _, costs = finder.targets(context.field)
    return bool(np.isfinite(costs).any())


def min_size(strategy: Strategy) -> int:
    """The smallest frontier cluster the strategy chases (its ``min_frontier_size``)."""
    return int(getattr(strategy.params, "min_frontier_size", DEFAULT_MIN_SIZE))
