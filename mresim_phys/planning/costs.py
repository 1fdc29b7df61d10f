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
(``None``) and every search runs its uniform-cost kernel, unchanged. With one:

* distance fields (``fields.distance_field``, hence frontier utilities and
  auctions) run :func:`dijkstra_weighted`, a binary-heap Dijkstra (Dial's
  buckets need moves of bounded cost);
* ``astar`` runs :func:`astar_weighted_kernel` (the octile heuristic, moves priced as
  above);
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
    MOVES,
    NO_PRED,
    OPEN,
    STRAIGHT,
    UNSEEN,
    diagonal_ok,
    flat_moves,
    heap_grow,
    heap_new,
    heap_pop,
    heap_push,
    octile,
    passes_corner,
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
    done = np.zeros(pad.size, dtype=np.bool_)
    fs, gs, nodes = heap_new(1024)
    dist[source] = 0.0
    size = heap_push(fs, gs, nodes, 0, 0.0, 0.0, source)
    step, beside_row, beside_col = flat_moves(wp)
    while size > 0:
        u, size = heap_pop(fs, gs, nodes, size)
        if done[u]:
            continue
        done[u] = True
        here = dist[u]
        for k in range(len(step)):
            v = u + step[k]
            if not pad[v] or done[v]:
                continue
            if beside_row[k] != 0:
                if not passes_corner(pad[u + beside_row[k]], pad[u + beside_col[k]]):
                    continue
                cost = here + move_cost(DIAGONAL, slow, u, v)
            else:
                cost = here + move_cost(STRAIGHT, slow, u, v)
            if cost <= limit and cost < dist[v]:
                dist[v], pred[v] = cost, u
                if size == len(fs):
                    fs, gs, nodes = heap_grow(fs, gs, nodes)
                size = heap_push(fs, gs, nodes, size, cost, cost, v)
    return dist, pred


@njit(cache=True, nogil=True)
def astar_weighted_kernel(
    pad: NDArray[np.bool_],
    wp: int,
    source: int,
    target: int,
    slow: FloatArray,
    g: FloatArray,
    pred: NDArray[np.int64],
    state: NDArray[np.uint8],
) -> tuple[float, int]:
    """``astar.astar_kernel`` (no labels) with terrain costs: moves priced by
    :func:`move_cost`; the same heap order, corner rule and outputs."""
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
            if dr != 0 and dc != 0:
                if not diagonal_ok(pad, wp, u, dr, dc):
                    continue
                cost = here + move_cost(DIAGONAL, slow, u, v)
            else:
                cost = here + move_cost(STRAIGHT, slow, u, v)
            if state[v] == UNSEEN or cost < g[v]:
                g[v], pred[v], state[v] = cost, u, OPEN
                f = cost + octile(ur + dr, uc + dc, tr, tc)
                if size == len(fs):
                    fs, gs, nodes = heap_grow(fs, gs, nodes)
                size = heap_push(fs, gs, nodes, size, f, cost, v)
    return (g[target] if state[target] != UNSEEN else np.inf), expanded
