"""Phase 4b (planning): path costs from one cell to a few goal cells, searched only as far as
one goal needs.

A teammate's bid in the frontier auction needs the path costs from the teammate to the
auction's few goals, and only one of them is asked for at a time: :func:`goal_costs`
runs the distance field's Dijkstra (``dial._dijkstra``, the same moves, bands and
window) from the start and stops as soon as that goal's cost is final, instead of
searching the whole window of ``limit``. A goal's cost is the same float whichever way
the search ends: a cell's cost is the least ``cost(u) + move`` over its neighbours ``u``
settled before it, whatever order they were expanded in. What the early stop leaves
unknown is bounded from below (:class:`GoalCosts`), which is all the auction needs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from mresim_phys.planning.costs import dijkstra_weighted
from mresim_phys.planning.dial import _dijkstra
from mresim_phys.planning.fields import _window, snap_to_passable
from mresim_phys.planning.grid import Box, Window
from mresim_phys.types import BoolGrid, FloatArray, IntArray


@dataclass(frozen=True)
class GoalCosts:
    """Exact path costs of some goals and a lower bound on the rest.

    ``found[i]`` is goal ``i``'s exact path cost, or inf where it is not known; every goal
    not known costs at least ``floor`` (inf: the unknown goals are unreachable).
    """

    found: FloatArray
    floor: float


def goal_costs(
    passable: BoolGrid,
    start_xy: tuple[float, float],
    goals_rc: IntArray,
    wanted: int,
    limit: float,
    box: Box | None,
    slowness: FloatArray | None = None,
    max_snap: float = 3.0,
) -> GoalCosts | None:
    """Path costs from ``start_xy`` (snapped as ``fields.distance_field`` snaps it) to the
    goal cells ``goals_rc`` (rows of (row, col)), up to ``limit``; the search stops once goal
    ``wanted``'s cost is final. None if the start has no passable cell within ``max_snap``.

    ``box`` is ``bbox(passable)``. With terrain (``slowness``) the search runs to ``limit``.
    """
    start = snap_to_passable(passable, start_xy, max_snap)
    if start is None or box is None:
        return None
    window = Window.around(passable, _window(start, box, limit))
    rows = goals_rc[:, 0] - window.origin[0]
    cols = goals_rc[:, 1] - window.origin[1]
    hp = window.pad.size // window.wp
    inside = (rows >= 0) & (rows < hp) & (cols >= 0) & (cols < window.wp)
    nodes = np.where(inside, rows * window.wp + cols, -1)
    if slowness is None:
        target = int(nodes[wanted])
        dist, _, band = _dijkstra(window.pad, window.wp, window.node(start), float(limit), target)
    else:
        slow = window.padded(slowness)
        dist, _ = dijkstra_weighted(window.pad, window.wp, window.node(start), float(limit), slow)
        band = -1
    found = np.where(inside, dist[np.maximum(nodes, 0)], np.inf)
    if band < 0:  # searched out to the limit: what it did not reach costs more
        return GoalCosts(found, float(limit))
    floor = min(band + 1.0, float(limit))
    return GoalCosts(np.where(found < band + 1, found, np.inf), floor)


@njit(cache=True, nogil=True)
def nearest_reached(costs: FloatArray, x: float, y: float) -> tuple[int, int]:
    """The cell with a finite cost in ``costs`` whose centre is nearest world point (x, y)
    (squared distance ``(c + 0.5 - x) ** 2 + (r + 0.5 - y) ** 2``), ties to the lower cost,
    then to the first in row-major order; (-1, -1) when no cost is finite. One pass over
    the grid, in place of a lexsort over every reached cell (``strategies.base``).

    >>> costs = np.full((3, 4), np.inf)
    >>> costs[0, 0], costs[2, 3], costs[1, 3] = 0.0, 4.0, 3.0
    >>> nearest_reached(costs, 3.6, 2.0)
    (1, 3)
    """
    rows, cols = costs.shape
    best_r, best_c = -1, -1
    best_d2, best_cost = np.inf, np.inf
    for r in range(rows):
        dy2 = (r + 0.5 - y) ** 2
        for c in range(cols):
            cost = costs[r, c]
            if not np.isfinite(cost):
                continue
            d2 = (c + 0.5 - x) ** 2 + dy2
            if best_r < 0 or d2 < best_d2 or (d2 == best_d2 and cost < best_cost):
                best_r, best_c, best_d2, best_cost = r, c, d2, cost
    return best_r, best_c
