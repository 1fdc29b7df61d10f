"""``astar``: optimal grid paths by A* with the octile heuristic (phase 4b).

The search is ``bestfirst.astar_kernel``: optimal paths, the same length as the distance
field's, equal f values broken toward the deeper node. With a slowness grid from known
terrain it prices a move by its octile length times the mean slowness of its two cells
(``costs.move_cost``); without one it runs on octile costs alone.

The kernel also serves the topological planner: given a label per cell and the set of
allowed labels, it searches only the corridor of node regions along a graph route.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mresim_phys.planning.base import GridPlanner, no_path
from mresim_phys.planning.bestfirst import astar_kernel
from mresim_phys.planning.catalog import PLANNERS
from mresim_phys.planning.grid import Window, search_arrays, walk_back
from mresim_phys.types import BoolGrid, FloatArray

NO_LABELS = np.zeros(0, dtype=np.int32)
NO_ALLOWED = np.zeros(0, dtype=np.bool_)


def astar_search(
    window: Window,
    start: tuple[int, int],
    goal: tuple[int, int],
    labels: NDArray[np.int32] = NO_LABELS,
    allowed: NDArray[np.bool_] = NO_ALLOWED,
    slowness: FloatArray | None = None,
) -> tuple[FloatArray, int]:
    """Cell-centre path (empty if unreachable) and expansion count of one A* search
    (``slowness``: the full-grid terrain cost multipliers, None = uniform)."""
    source, target = window.node(start), window.node(goal)
    g, pred, state = search_arrays(window.pad.size)
    slow = None if slowness is None else window.padded(slowness)
    cost, expanded = astar_kernel(
        window.pad, window.wp, source, target, labels, allowed, slow, g, pred, state
    )
    if not np.isfinite(cost):
        return no_path(), expanded
    return window.points(walk_back(pred, target)), expanded


@PLANNERS.register
class AStar(GridPlanner):
    """Optimal 8-connected grid paths: A* with the octile heuristic, no corner cutting."""

    name = "astar"

    def search(
        self,
        passable: BoolGrid,
        start: tuple[int, int],
        goal: tuple[int, int],
        slowness: FloatArray | None = None,
    ) -> FloatArray:
        """The optimal cell-centre path; (0, 2) if the goal is unreachable."""
        return weighted_astar(passable, start, goal, slowness)


def weighted_astar(
    passable: BoolGrid,
    start: tuple[int, int],
    goal: tuple[int, int],
    slowness: FloatArray | None,
) -> FloatArray:
    """A* over the whole passable window, priced by ``slowness`` (None: uniform)."""
    window = Window.of(passable)
    assert window is not None  # the start is passable
    return astar_search(window, start, goal, slowness=slowness)[0]
