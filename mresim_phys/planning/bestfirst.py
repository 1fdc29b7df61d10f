"""Phase 4b (planning): the one binary-heap grid search, A* with the octile heuristic.

:func:`astar_kernel` serves every heap search of the planners, uniform or priced by
terrain:

* ``astar`` (and ``jps`` and ``topological`` when they fall back to it) searches toward a
  target, optionally inside a corridor of labelled regions;
* with a slowness grid (``planning.costs``) a move costs ``costs.move_cost``: its octile
  length times the mean slowness of its two cells, >= the octile length, so the heuristic
  stays admissible and consistent. Without one (``slow=None``) numba compiles the kernel
  with the plain octile costs, the pricing branch pruned away: the same operations, in
  the same order, as a kernel written without terrain.

The octile distance is the exact path cost on an obstacle-free grid under the move rules
(8-connected, octile costs, no squeezing between two blocked cells), so it is admissible
and consistent: every cell is expanded at most once and the path is optimal. Equal f
values are broken toward the deeper node (``grid.heap_push``).
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

from mresim_phys.planning.costs import move_cost
from mresim_phys.planning.grid import (
    CLOSED,
    DIAGONAL,
    MOVES,
    NO_PRED,
    OPEN,
    STRAIGHT,
    UNSEEN,
    diagonal_ok,
    heap_add,
    heap_start,
    octile,
    pop_open,
)
from mresim_phys.types import FloatArray


@njit(cache=True, nogil=True)
def astar_kernel(
    pad: NDArray[np.bool_],
    wp: int,
    source: int,
    target: int,
    labels: NDArray[np.int32],
    allowed: NDArray[np.bool_],
    slow: FloatArray | None,
    g: FloatArray,
    pred: NDArray[np.int64],
    state: NDArray[np.uint8],
) -> tuple[float, int]:
    """A* from ``source`` to ``target`` over a flat padded mask (border blocked).

    With a non-empty ``labels`` (one per cell) a cell may be entered only if
    ``allowed[labels[cell] + 1]``. ``slow``: the padded slowness of every cell (moves
    priced by ``costs.move_cost``), None for octile costs. ``g``, ``pred`` and ``state``
    come from ``grid.search_arrays``; ``pred`` is filled in. Returns the path cost (inf if
    unreachable) and the number of expanded cells.
    """
    restricted = labels.size > 0
    tr, tc = target // wp, target % wp
    g[source], pred[source], state[source] = 0.0, NO_PRED, OPEN
    heap, size = heap_start(1024, source, octile(source // wp, source % wp, tr, tc))
    expanded = 0
    while True:
        u, size = pop_open(heap, size, state)
        if u < 0:
            break
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
                cost = here + (DIAGONAL if slow is None else move_cost(DIAGONAL, slow, u, v))
            else:
                cost = here + (STRAIGHT if slow is None else move_cost(STRAIGHT, slow, u, v))
            if state[v] == UNSEEN or cost < g[v]:
                g[v], pred[v], state[v] = cost, u, OPEN
                f = cost + octile(ur + dr, uc + dc, tr, tc)
                heap, size = heap_add(heap, size, f, cost, v)
    return (g[target] if state[target] != UNSEEN else np.inf), expanded
