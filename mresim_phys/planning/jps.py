"""``jps``: Jump Point Search (Harabor and Grastien 2011) under our move rules (phase 4b).

JPS is A* that expands only "jump points": from a node it scans straight and diagonal
rays, skipping every cell whose optimal paths are symmetric to ones through its parent,
and stops where a path could turn optimally (a forced neighbour) or at the goal. Paths
are optimal, the same lengths as ``astar``'s; in open space far fewer nodes enter the
heap.

The pruning rules are those of the movement model where a diagonal step is forbidden
only when BOTH orthogonal cells it passes are blocked (corner cutting past a single
blocked cell is allowed), i.e. exactly the rule of :mod:`mresim_phys.planning.grid`:

* straight move (here: along columns, direction ``dc``): a neighbour diagonally ahead,
  ``(+-1, dc)``, is forced when the cell beside it, ``(+-1, 0)``, is blocked (and the
  cell ahead is free, so the diagonal is allowed);
* diagonal move ``(dr, dc)``: ``(dr, -dc)`` is forced when ``(0, -dc)`` is blocked and
  ``(dr, 0)`` free; ``(-dr, dc)`` when ``(-dr, 0)`` is blocked and ``(0, dc)`` free; and a
  diagonal ray stops wherever one of its two straight rays finds a jump point.

The tests check path lengths against a reference Dijkstra on random grids.

Terrain: jump points assume every move of a kind costs the same, so with known slow
terrain (a ``slowness`` grid, ``planning.costs``) the planner runs cost-aware ``astar``.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

from mresim_phys.planning.astar import weighted_astar
from mresim_phys.planning.base import GridPlanner, no_path
from mresim_phys.planning.catalog import PLANNERS
from mresim_phys.planning.grid import (
    CLOSED,
    MOVES,
    NO_PRED,
    OPEN,
    UNSEEN,
    Window,
    diagonal_ok,
    heap_add,
    heap_start,
    octile,
    pop_open,
    search_arrays,
    search_window,
    walk_back,
)
from mresim_phys.types import BoolGrid, FloatArray

_DIRECTIONS = MOVES  # a direction is its index in MOVES (raster order; see _add)


@njit(cache=True, nogil=True)
def _jump_straight(pad: NDArray[np.bool_], wp: int, u: int, dr: int, dc: int, target: int) -> int:
    """First jump point on the straight ray from ``u`` (exclusive); -1 if none."""
    step = dr * wp + dc
    side = 1 if dr != 0 else wp  # offset to the cells beside the ray
    while True:
        v = u + step
        if not pad[v]:
            return -1
        if v == target:
            return v
        if (not pad[v - side] and pad[v - side + step]) or (
            not pad[v + side] and pad[v + side + step]
        ):
            return v
        u = v


@njit(cache=True, nogil=True)
def _jump_diagonal(pad: NDArray[np.bool_], wp: int, u: int, dr: int, dc: int, target: int) -> int:
    """First jump point on the diagonal ray from ``u`` (exclusive); -1 if none."""
    vertical = dr * wp
    while True:
        if not diagonal_ok(pad, wp, u, dr, dc):
            return -1
        v = u + vertical + dc
        if not pad[v]:
            return -1
        if v == target:
            return v
        if (pad[v - dc + vertical] and not pad[v - dc]) or (
            pad[v - vertical + dc] and not pad[v - vertical]
        ):
            return v
        if _jump_straight(pad, wp, v, 0, dc, target) >= 0:
            return v
        if _jump_straight(pad, wp, v, dr, 0, target) >= 0:
            return v
        u = v


@njit(cache=True, nogil=True, inline="always")
def _add(out: NDArray[np.int64], count: int, dr: int, dc: int, keep: bool) -> int:
    """Append direction (dr, dc) (its index in _DIRECTIONS) when ``keep``."""
    if not keep:
        return count
    k = (dr + 1) * 3 + (dc + 1)
    out[count] = k - 1 if k > 4 else k
    return count + 1


@njit(cache=True, nogil=True)
def _successor_directions(
    pad: NDArray[np.bool_], wp: int, u: int, parent: int, out: NDArray[np.int64]
) -> int:
    """Directions (indices into _DIRECTIONS) not pruned at ``u``; returns how many."""
    if parent == NO_PRED:
        for i in range(8):
            out[i] = i
        return 8
    dr = int(np.sign(u // wp - parent // wp))
    dc = int(np.sign(u % wp - parent % wp))
    if dr != 0 and dc != 0:
        ahead_r, ahead_c = pad[u + dr * wp], pad[u + dc]
        count = _add(out, 0, dr, 0, ahead_r)
        count = _add(out, count, 0, dc, ahead_c)
        count = _add(out, count, dr, dc, ahead_r or ahead_c)
        count = _add(out, count, dr, -dc, ahead_r and not pad[u - dc])
        return _add(out, count, -dr, dc, ahead_c and not pad[u - dr * wp])
    ahead = pad[u + dr * wp + dc]
    side, sr, sc = (1, 0, 1) if dr != 0 else (wp, 1, 0)  # offset and direction of +side
    count = _add(out, 0, dr, dc, ahead)
    count = _add(out, count, dr + sr, dc + sc, ahead and not pad[u + side])
    return _add(out, count, dr - sr, dc - sc, ahead and not pad[u - side])


@njit(cache=True, nogil=True)
def jps_kernel(
    pad: NDArray[np.bool_],
    wp: int,
    source: int,
    target: int,
    g: FloatArray,
    pred: NDArray[np.int64],
    state: NDArray[np.uint8],
) -> tuple[float, int]:
    """Jump point search (arrays from ``search_arrays``; ``pred`` links jump points).

    Returns the cost (inf if unreachable) and the number of expanded jump points.
    """
    tr, tc = target // wp, target % wp
    g[source], pred[source], state[source] = 0.0, NO_PRED, OPEN
    heap, size = heap_start(256, source, octile(source // wp, source % wp, tr, tc))
    directions = np.empty(8, dtype=np.int64)
    expanded = 0
    while True:
        u, size = pop_open(heap, size, state)
        if u < 0:
            break
        expanded += 1
        if u == target:
            break
        ur, uc = u // wp, u % wp
        for k in range(_successor_directions(pad, wp, u, pred[u], directions)):
            dr, dc = _DIRECTIONS[directions[k]]
            if dr != 0 and dc != 0:
                v = _jump_diagonal(pad, wp, u, dr, dc, target)
            else:
                v = _jump_straight(pad, wp, u, dr, dc, target)
            if v < 0 or state[v] == CLOSED:
                continue
            vr, vc = v // wp, v % wp
            cost = g[u] + octile(ur, uc, vr, vc)
            if state[v] == UNSEEN or cost < g[v]:
                g[v], pred[v], state[v] = cost, u, OPEN
                f = cost + octile(vr, vc, tr, tc)
                heap, size = heap_add(heap, size, f, cost, v)
    return (g[target] if state[target] != UNSEEN else np.inf), expanded


@njit(cache=True, nogil=True)
def _fill_segments(jumps: NDArray[np.int64], wp: int) -> NDArray[np.int64]:
    """Every cell of a path given by its jump points (each segment straight or diagonal)."""
    total = 1
    for i in range(1, len(jumps)):
        a, b = jumps[i - 1], jumps[i]
        total += max(abs(b // wp - a // wp), abs(b % wp - a % wp))
    out = np.empty(total, dtype=np.int64)
    out[0], k = jumps[0], 1
    for i in range(1, len(jumps)):
        a, b = jumps[i - 1], jumps[i]
        step = np.sign(b // wp - a // wp) * wp + np.sign(b % wp - a % wp)
        while a != b:
            a += step
            out[k], k = a, k + 1
    return out


def jps_search(
    window: Window, start: tuple[int, int], goal: tuple[int, int]
) -> tuple[FloatArray, int]:
    """Cell-centre path (empty if unreachable) and expansion count of one JPS search."""
    source, target = window.node(start), window.node(goal)
    g, pred, state = search_arrays(window.pad.size)
    cost, expanded = jps_kernel(window.pad, window.wp, source, target, g, pred, state)
    if not np.isfinite(cost):
        return no_path(), expanded
    cells = _fill_segments(walk_back(pred, target), window.wp)
    return window.points(cells), expanded


@PLANNERS.register
class JumpPointSearch(GridPlanner):
    """Jump point search: astar's optimal lengths with fewer expansions in open areas."""

    name = "jps"

    def search(
        self,
        passable: BoolGrid,
        start: tuple[int, int],
        goal: tuple[int, int],
        slowness: FloatArray | None = None,
    ) -> FloatArray:
        """An optimal cell-centre path; (0, 2) if the goal is unreachable. With known slow
        terrain (``slowness``) the pruning is not valid: cost-aware A* plans instead."""
        if slowness is not None:
            return weighted_astar(passable, start, goal, slowness)
        return search_window(passable, start, goal, jps_search)
