"""Phase 4b (planning): traversal costs on known terrain (``terrain:`` in a scenario).

A robot's known terrain is a speed factor per cell in (0, 1] (1 where it has not sensed
the ground, :mod:`mresim_phys.knowledge.terrain`). The planners read its inverse, the
``slowness`` of a cell (``1 / factor`` >= 1: how many times longer crossing it takes),
and price a move between neighbouring cells ``u`` and ``v`` as::

    cost(u -> v) = octile cost (1 or sqrt 2) * (slowness[u] + slowness[v]) / 2

i.e. half of the move is driven on each cell: the time the move takes, in units of
open-floor steps. Every move still costs at least its octile length, so the octile
heuristic of A* stays admissible and consistent, and a search bounded by a cost
``limit`` still stays within that Chebyshev radius of its start.

Without terrain, or while every known factor is 1, there is no slowness grid at all
(``None``) and every search runs on uniform costs. With one:

* distance fields (``fields.distance_field``, hence frontier utilities and
  auctions) run :func:`dijkstra_weighted`, a binary-heap Dijkstra (Dial's
  buckets need moves of bounded cost);
* ``astar`` runs ``bestfirst.astar_kernel`` with the slowness grid (the octile
  heuristic, moves priced by :func:`move_cost`);
* ``jps`` falls back to ``astar``: its pruning assumes uniform costs;
* ``topological`` falls back to ``astar`` over the whole window (its region graph and
  corridor search are uniform-cost);
* smoothing takes shortcuts only across cells of slowness 1.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

from mresim_phys.planning.grid import (
    CLOSED,
    DIAGONAL,
    STRAIGHT,
    flat_moves,
    heap_add,
    heap_start,
    passes_corner,
    pop_open,
)
from mresim_phys.types import FloatArray

NO_FIELD_PRED = -9999  # "no predecessor" in a distance field (``fields._NO_PRED``)


def slowness_of(terrain: NDArray[np.floating] | None) -> FloatArray | None:
    """``1 / terrain`` as float64, or None without terrain or where it is all 1 (uniform)."""
    if terrain is None or bool((terrain >= 1.0).all()):
        return None
    slowness: FloatArray = 1.0 / terrain.astype(np.float64)
    return slowness


@njit(cache=True, nogil=True, inline="always")
def move_cost(base: float, slow: FloatArray, u: int, v: int) -> float:
    """The cost of a move of octile length ``base`` from cell ``u`` to cell ``v``."""
    cost: float = base * 0.5 * (slow[u] + slow[v])
    return cost


@njit(cache=True, nogil=True)
def dijkstra_weighted(
    pad: NDArray[np.bool_], wp: int, source: int, limit: float, slow: FloatArray
) -> tuple[FloatArray, NDArray[np.int32]]:
    """``fields._dijkstra`` with terrain costs: the same moves, corner rule and outputs
    (float64 costs, flat int32 predecessors, -9999 = none), on a binary heap."""
    dist = np.full(pad.size, np.inf)
    pred = np.full(pad.size, NO_FIELD_PRED, dtype=np.int32)
    state = np.zeros(pad.size, dtype=np.uint8)
    dist[source] = 0.0
    heap, size = heap_start(1024, source, 0.0)
    step, beside_row, beside_col = flat_moves(wp)
    while True:
        u, size = pop_open(heap, size, state)
        if u < 0:
            break
        here = dist[u]
        for k in range(len(step)):
            v = u + step[k]
            if not pad[v] or state[v] == CLOSED:
                continue
            if beside_row[k] != 0:
                if not passes_corner(pad[u + beside_row[k]], pad[u + beside_col[k]]):
                    continue
                cost = here + move_cost(DIAGONAL, slow, u, v)
            else:
                cost = here + move_cost(STRAIGHT, slow, u, v)
            if cost <= limit and cost < dist[v]:
                dist[v], pred[v] = cost, u
                heap, size = heap_add(heap, size, cost, cost, v)
    return dist, pred
