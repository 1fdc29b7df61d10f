"""Candidate targets (phase 4, decide): the places a ``policy`` robot may choose to go.

A choice action picks one slot of a fixed table (docs/learning.md):

* slot 0, ``continue``: keep heading for the robot's current target (stand if it has none);
* slots 1..F, its frontier clusters, nearest by path first: each cluster's target cell
  (the cheapest cell from which the cluster is in reach, ``knowledge.targets``), as
  ``frontier`` goes to it; a frontier it reached and faced in vain is set aside and given
  up as ``frontier`` does (``strategies/giveup.py``): the cells it tried are offered only
  when no untried frontier is left, and never after two tries;
* slots F+1..F+M, meetings: the last reported positions of the M teammates nearest in a
  straight line that it does not presume lost;
* the last slot, the base station.

A slot is valid when it holds a place the robot can reach on its own map (a meeting point
or the base: its cell, or the passable cell nearest to it within ``SNAP`` cells). All of it
is read from the robot's view.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mresim_phys.knowledge.frontiers import Frontiers, frontiers_in
from mresim_phys.knowledge.targets import TargetFinder, target_reach
from mresim_phys.knowledge.teammates import BASE_NAME
from mresim_phys.planning.fields import snap_to_passable
from mresim_phys.strategies.base import PlanContext, RobotView
from mresim_phys.strategies.frontier import nearest_cell_centre
from mresim_phys.strategies.giveup import Tried
from mresim_phys.types import FloatArray, IntArray

CONTINUE = 0  # the slot that keeps the current target
SNAP = 8.0  # cells: how far from a meeting point or the base its target cell may lie


@dataclass(frozen=True)
class Candidates:
    """The slot table: ``points`` (S, 2) world (x, y), ``costs`` (S,) path cost from the
    robot (inf: unreachable or empty), ``valid`` (S,) which slots may be chosen, ``looks``
    (S, 2) the point a robot arriving at a slot's place turns to face (a frontier slot: its
    cluster's cell nearest the target; NaN: none)."""

    points: FloatArray
    costs: FloatArray
    valid: np.ndarray
    looks: FloatArray
    clusters: tuple[IntArray | None, ...] = ()

    @classmethod
    def empty(cls, slots: int) -> Candidates:
        """A table with only ``continue`` valid (a robot not asked now)."""
        valid = np.zeros(slots, dtype=bool)
        valid[CONTINUE] = True
        return cls(np.zeros((slots, 2)), np.full(slots, np.inf), valid, no_looks(slots))


def slot_count(frontiers: int, meet: int) -> int:
    """Slots of a table with ``frontiers`` frontier and ``meet`` meeting slots."""
    return 1 + frontiers + meet + 1


def find_candidates(
    view: RobotView,
    context: PlanContext,
    frontiers: int,
    meet: int,
    current: tuple[float, float] | None,
    tried: Tried,
) -> Candidates:
    """The slot table of ``view`` (module docstring); ``current`` is the robot's target,
    ``tried`` the frontiers it reached in vain."""
    slots = slot_count(frontiers, meet)
    points, costs = np.zeros((slots, 2)), np.full(slots, np.inf)
    valid = np.zeros(slots, dtype=bool)
    valid[CONTINUE] = True
    looks = no_looks(slots)
    if current is not None:
        points[CONTINUE] = current
    field = context.field
    clusters: list[IntArray | None] = [None] * slots
    found, targets, target_costs = frontier_targets(view, context, tried)
    order = np.argsort(target_costs, kind="stable")[:frontiers]
    for slot, j in enumerate(order, start=1):
        if np.isfinite(target_costs[j]):
            row, col = targets[j]
            points[slot] = (col + 0.5, row + 0.5)
            costs[slot], valid[slot] = target_costs[j], True
            cells = clusters[slot] = found.cells_rc[found.cluster_of == j]
            looks[slot] = nearest_cell_centre(cells, row, col)
    places = [*meeting_points(view, meet), view.base_position]
    first = 1 + frontiers
    for offset, point in enumerate(places):
        slot = first + offset if offset < len(places) - 1 else slots - 1
        cell = snap_to_passable(context.passable, point, SNAP)
        if cell is not None and field.reachable(*cell):
            points[slot] = (cell[1] + 0.5, cell[0] + 0.5)
            costs[slot], valid[slot] = (
                field.cost_at(np.array([cell[0]]), np.array([cell[1]]))[0],
                True,
            )
    return Candidates(points, costs, valid, looks, tuple(clusters))


def frontier_targets(
    view: RobotView, context: PlanContext, tried: Tried
) -> tuple[Frontiers, IntArray, FloatArray]:
    """(frontiers, target cells, path costs): the untried frontiers, or with none reachable
    the set-aside ones not given up, their targets off the spots tried in vain."""
    reach = target_reach(view.clearance)
    found = frontiers_in(view.belief, context.free_box, exclude=tried.set_aside)
    targets, costs = TargetFinder.of(found, context.passable, reach).targets(context.field)
    if np.isfinite(costs).any() or not tried.set_aside_any:
        return found, targets, costs
    found = frontiers_in(view.belief, context.free_box, exclude=tried.given_up)
    cells = tried.target_cells(context.passable)
    targets, costs = TargetFinder.of(found, cells, reach).targets(context.field)
    return found, targets, costs


def no_looks(slots: int) -> FloatArray:
    """A ``looks`` column with no point to face."""
    return np.full((slots, 2), np.nan)


def meeting_points(view: RobotView, meet: int) -> list[tuple[float, float]]:
    """The last reported positions of the ``meet`` teammates nearest in a straight line,
    not presumed lost (ties: the team's order)."""
    lost = view.lost
    x, y = view.position
    known = [
        (float(np.hypot(info.position[0] - x, info.position[1] - y)), view.tie_rank(name),
         (float(info.position[0]), float(info.position[1])))
        for name, info in view.teammates.items()
        if name not in (view.name, BASE_NAME) and name not in lost
    ]  # fmt: skip
    known.sort(key=lambda k: (k[0], k[1]))
    return [k[2] for k in known[:meet]]
