"""Phase 4b (planning): the one binary-heap grid search, A* with the octile heuristic.

:func:`astar_kernel` serves every heap search of the planners, uniform or priced by
terrain:

* ``astar`` (and ``jps`` and ``topological`` when they fall back to it) searches toward a
  target, optionally inside a corridor of labelled regions;
* steered by a ``guide`` (a search from the target, ``planning.goal_fields``) in place of
  the octile distance, it finds a teammate's exact path cost to an auction goal along the
  near-best paths (:func:`guided`);
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

GUIDE_DEFLATION = 1e-6  # a guide's costs count for this much less (see :func:`guided`)
# A guide: the flat costs of a search from the target, the shift (rows, cols) from this
# search's window to that one's, its width and height, and the cost below which its costs
# are final
Guide = tuple[FloatArray, int, int, int, int, float]


@njit(cache=True, nogil=True, inline="always")
def estimate(r: int, c: int, tr: int, tc: int, guide: Guide | None) -> float:
    """The heuristic at window cell (``r``, ``c``) for target (``tr``, ``tc``): the octile
    distance, or with a ``guide`` :func:`guided`."""
    if guide is None:
        return octile(r, c, tr, tc)
    return guided(r, c, guide)


@njit(cache=True, nogil=True, inline="always")
def guided(r: int, c: int, guide: Guide) -> float:
    """A guide's cost at window cell (``r``, ``c``) (where it is final; its final bound
    elsewhere), less ``GUIDE_DEFLATION`` of it.

    The guide is a search from the target on the same mask: its final costs are the
    reverse path costs, within rounding of the forward ones, so it is a consistent
    heuristic up to rounding (and the bound, a lower bound of every cost not final, keeps
    it consistent across the edge of what is final). Deflated by a millionth, each move
    keeps a margin of at least a millionth of its cost: far above both the rounding of
    sums of moves (``c**2 * 2**-53``) and the heap's tie width (``grid.TIE``), so a cell is
    expanded only after every neighbour that offers it a cheaper cost, and the cost found
    is the least float sum over the paths: the distance field's own.
    """
    dist, dr, dc, gw, gh, final = guide
    gr, gc = r + dr, c + dc
    cost = final
    if 0 <= gr < gh and 0 <= gc < gw and dist[gr * gw + gc] < final:
        cost = dist[gr * gw + gc]
    return (1.0 - GUIDE_DEFLATION) * cost


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
    guide: Guide | None = None,
) -> tuple[float, int]:
    """A* from ``source`` to ``target`` over a flat padded mask (border blocked).

    With a non-empty ``labels`` (one per cell) a cell may be entered only if
    ``allowed[labels[cell] + 1]``. ``slow``: the padded slowness of every cell (moves
    priced by ``costs.move_cost``), None for octile costs. ``g``, ``pred`` and ``state``
    come from ``grid.search_arrays``; ``pred`` is filled in. ``guide``: the costs of a
    search from the target to steer by (:func:`guided`) in place of the octile distance.
    Returns the path cost (inf if unreachable) and the number of expanded cells.
    """
    restricted = labels.size > 0
    tr, tc = target // wp, target % wp
    g[source], pred[source], state[source] = 0.0, NO_PRED, OPEN
    heap, size = heap_start(1024, source, estimate(source // wp, source % wp, tr, tc, guide))
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
                f = cost + estimate(ur + dr, uc + dc, tr, tc, guide)
                heap, size = heap_add(heap, size, f, cost, v)
    return (g[target] if state[target] != UNSEEN else np.inf), expanded
