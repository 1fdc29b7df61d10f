"""``astar``: optimal grid paths by A* with the octile heuristic (phase 4b).

The octile distance is the exact path cost on an obstacle-free grid under the move rules
(8-connected, octile costs, no squeezing between two blocked cells), so it is admissible
and consistent: every cell is expanded at most once and the path is optimal, the same
length as the distance field's. Equal f values are broken toward the deeper node.

With a slowness grid from known terrain a search runs ``costs.astar_weighted_kernel``
instead: a move costs its octile length times the mean slowness of its two cells (>= the
octile length, so the heuristic stays admissible and consistent). Without one the uniform
kernel below runs, unchanged.

The kernel also serves the topological planner: given a label per cell and the set of
allowed labels, it searches only the corridor of node regions along a graph route.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

from mresim_phys.planning.base import PLANNERS, GridPlanner, no_path
from mresim_phys.planning.costs import astar_weighted_kernel
from mresim_phys.planning.grid import (
    CLOSED,
    DIAGONAL,
    MOVES,
    NO_PRED,
    OPEN,
    STRAIGHT,
    UNSEEN,
    Window,
    diagonal_ok,
    heap_grow,
    heap_new,
    heap_pop,
    heap_push,
    octile,
    search_arrays,
    walk_back,
)
from mresim_phys.types import BoolGrid, FloatArray

NO_LABELS = np.zeros(0, dtype=np.int32)
NO_ALLOWED = np.zeros(0, dtype=np.bool_)


@njit(cache=True, nogil=True)
def astar_kernel(
    pad: NDArray[np.bool_],
    wp: int,
    source: int,
    target: int,
    labels: NDArray[np.int32],
    allowed: NDArray[np.bool_],
    g: FloatArray,
    pred: NDArray[np.int64],
    state: NDArray[np.uint8],
) -> tuple[float, int]:
    """A* from ``source`` to ``target`` over a flat padded mask (border blocked).

    With a non-empty ``labels`` (one per cell) a cell may be entered only if
    ``allowed[labels[cell] + 1]``. ``g``, ``pred`` and ``state`` come from
    ``search_arrays``; ``pred`` is filled in. Returns the path cost (inf if unreachable)
    and the number of expanded cells.
    """
    restricted = labels.size > 0
    tr, tc = target // wp, target % wp
    fs, gs, nodes = heap_new(1024)
    g[source], pred[source], state[source] = 0.0, NO_PRED, OPEN
    size = heap_push(fs, gs, nodes, 0, octile(source // wp, source % wp, tr, tc), 0.0, source)
    expanded = 0
    while size > 0:
        u, size = heap_pop(fs, gs, nodes, size)
        if state[u] == CLOSED:
            continue
        state[u] = CLOSED
        expanded += 1
        if u == target:
            break
        here = g[u]
        ur, uc = u // wp, u % wp
        for dr, dc in MOVES:
            v = u + dr * wp + dc
            if not pad[v] or state[v] == CLOSED:
                continue
            if restricted and not allowed[labels[v] + 1]:
                continue
            if dr != 0 and dc != 0:
                if not diagonal_ok(pad, wp, u, dr, dc):
                    continue
                cost = here + DIAGONAL
            else:
                cost = here + STRAIGHT
            if state[v] == UNSEEN or cost < g[v]:
                g[v], pred[v], state[v] = cost, u, OPEN
                f = cost + octile(ur + dr, uc + dc, tr, tc)
                if size == len(fs):
                    fs, gs, nodes = heap_grow(fs, gs, nodes)
                size = heap_push(fs, gs, nodes, size, f, cost, v)
    return (g[target] if state[target] != UNSEEN else np.inf), expanded


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
    if slowness is None:
        cost, expanded = astar_kernel(
            window.pad, window.wp, source, target, labels, allowed, g, pred, state
        )
    else:  # terrain costs, over the whole window (``labels`` are not used)
        slow = window.padded(slowness)
        cost, expanded = astar_weighted_kernel(
            window.pad, window.wp, source, target, slow, g, pred, state
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
