"""Phase 4b (planning): the distance field's Dijkstra kernel, whole or paused at cost bounds.

``_dijkstra`` is the engine of ``fields.distance_field`` and ``goals.goal_costs``: Dijkstra
with Dial's bucket queue over a flat padded mask (``grid.Window``) with the move rules of
``planning.grid``. ``_expand`` is its loop, which can stop before a given band and go on
later from the state it left: :class:`PausedSearch` holds that state, so a strategy that
needs only the near part of a field (the frontier auction's best few frontiers) pays only
for that part, and gets the whole field, byte for byte the same, if it turns out to need it.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

from mresim_phys.planning.grid import DIAGONAL, STRAIGHT, Box, Window, flat_moves, passes_corner
from mresim_phys.types import BoolGrid, FloatArray

_NO_PRED = -9999  # "no predecessor" (the marker scipy.sparse.csgraph uses)
NEVER = np.iinfo(np.int64).max  # a band no search reaches: ``_expand`` runs to the end


@njit(cache=True, nogil=True)
def _expand(
    pad: NDArray[np.bool_],
    wp: int,
    dist: FloatArray,
    pred: NDArray[np.int32],
    ring: NDArray[np.int32],
    sizes: NDArray[np.int64],
    band: int,
    limit: float,
    stop_at: int,
    stop_band: int,
) -> int:
    """Expand bands from ``band`` on (see :func:`_dijkstra`); the band it stopped before,
    or -1 once the queue ran out. It stops before expanding band ``stop_band`` (every cell
    costing less than ``stop_band`` then has its final cost) or, with a ``stop_at`` cell
    (>= 0), before the first band ``b`` with ``dist[stop_at] < b + 1``. Called again with
    the band it returned and the same arrays it goes on as if it had never stopped."""
    step, beside_row, beside_col = flat_moves(wp)
    while sizes[band % 3] + sizes[(band + 1) % 3] > 0:
        if band >= stop_band:
            return band
        if stop_at >= 0 and dist[stop_at] < band + 1:
            return band
        slot = band % 3
        for j in range(sizes[slot]):
            u = ring[slot, j]
            here = dist[u]
            if int(here) != band:
                continue  # moved to an earlier band, already expanded
            for k in range(len(step)):
                v = u + step[k]
                if not pad[v]:
                    continue
                if beside_row[k] != 0:  # a diagonal move
                    if not passes_corner(pad[u + beside_row[k]], pad[u + beside_col[k]]):
                        continue
                    cost = here + DIAGONAL
                else:
                    cost = here + STRAIGHT
                old = dist[v]
                if cost <= limit and cost < old:
                    dist[v], pred[v] = cost, u
                    target = int(cost)
                    if old == np.inf or int(old) != target:  # not yet in band target's bucket
                        ring[target % 3, sizes[target % 3]] = v
                        sizes[target % 3] += 1
        sizes[slot] = 0
        band += 1
    return -1


@njit(cache=True, nogil=True)
def _start(
    pad: NDArray[np.bool_], source: int
) -> tuple[FloatArray, NDArray[np.int32], NDArray[np.int32], NDArray[np.int64]]:
    """A search's arrays with only ``source`` queued (cost 0): dist, pred, ring, sizes."""
    dist = np.full(pad.size, np.inf)
    pred = np.full(pad.size, _NO_PRED, dtype=np.int32)
    ring = np.empty((3, np.count_nonzero(pad)), dtype=np.int32)
    sizes = np.zeros(3, dtype=np.int64)
    dist[source] = 0.0
    ring[0, 0], sizes[0] = source, 1
    return dist, pred, ring, sizes


@njit(cache=True, nogil=True)
def _dijkstra(
    pad: NDArray[np.bool_], wp: int, source: int, limit: float, stop_at: int = -1
) -> tuple[FloatArray, NDArray[np.int32], int]:
    """Dijkstra over a flat padded mask (border cells blocked) with the module move rules.

    Dial's bucket queue: band ``b`` holds the cells whose cost is in ``[b, b + 1)``. Every
    move costs >= 1, so expanding band ``b`` only reaches bands ``b + 1`` and ``b + 2``: its
    cells are final when it is expanded, in any order, and a ring of 3 buckets replaces the
    heap (same costs, ~4x faster). A cell enters a band's bucket only when its cost moves
    into that band (a cheaper cost within the same band finds it queued there already), so
    no bucket outgrows the passable cell count; an entry whose cell has since moved to an
    earlier band is skipped. Costs above ``limit`` are never stored.

    With a ``stop_at`` cell (>= 0) the search stops before expanding the first band ``b`` with
    ``dist[stop_at] < b + 1``: every cell costing less than ``b + 1`` then has its final
    cost, the others cost at least ``b + 1``. Returns (costs, predecessors, ``b``), ``b`` =
    -1 when the search ran out of cells (no ``stop_at``, or it is not reached within ``limit``).
    """
    dist, pred, ring, sizes = _start(pad, source)
    band = _expand(pad, wp, dist, pred, ring, sizes, 0, limit, stop_at, NEVER)
    return dist, pred, band


@njit(cache=True, nogil=True)
def _start_paused(
    pad: NDArray[np.bool_], source: int
) -> tuple[FloatArray, NDArray[np.int32], NDArray[np.int32], NDArray[np.int64]]:
    """:func:`_start` called from Python. Numba's cache can lose the boxing environment of
    a kernel that another cached kernel (here ``_dijkstra``) also calls, and its arrays
    then fail to reach Python ("'descr' is NULL"); each caller from Python is a kernel of
    its own (``knowledge.mapping._fold_alone`` is the other)."""
    return _start(pad, source)


class PausedSearch:
    """An unbounded Dijkstra from one cell over a window, run band by band on demand.

    :meth:`run_below` expands the bands below a cost bound and returns; the costs below
    the bound are then final, and the costs at or above it are not (they are provisional
    or inf). Run below ``inf`` it has the arrays of ``_dijkstra`` over the same window,
    identical: pausing only splits the same loop.
    """

    def __init__(self, passable: BoolGrid, start: tuple[int, int], box: Box) -> None:
        self.start = start  # full-grid (row, col) of the source
        self.window = Window.around(passable, box)
        self.dist, self.pred, self._ring, self._sizes = _start_paused(
            self.window.pad, self.window.node(start)
        )
        self._band = 0  # the next band to expand; -1 once the queue ran out
        self.final_below = 0.0  # costs below this are final

    @property
    def finished(self) -> bool:
        """Whether every reachable cell has its final cost."""
        return self._band < 0

    @property
    def settled_below(self) -> float:
        """Costs below this are final: those of the band the search stopped before too
        (every cell that can lower one of them costs a move less, so was expanded)."""
        return np.inf if self._band < 0 else self._band + 1.0

    def run_below(self, bound: float, stop_at: int = -1) -> None:
        """Expand every band below ``bound`` (inf: to the end); with a ``stop_at`` node,
        stop sooner, once its cost is final."""
        if self.finished or bound <= self.final_below:
            return
        stop = NEVER if bound == np.inf else int(np.ceil(bound))
        self._band = _expand(
            self.window.pad, self.window.wp, self.dist, self.pred, self._ring, self._sizes,
            self._band, np.inf, stop_at, stop,
        )  # fmt: skip
        self.final_below = np.inf if self._band < 0 else float(self._band)
