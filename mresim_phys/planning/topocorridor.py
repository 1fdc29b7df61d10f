"""Planning (phase 4b): the grid search of a topological query, confined to a corridor.

The last step of a ``topological`` query (:mod:`mresim_phys.planning.topological`): once the
ends are anchored and the node route found, search the grid from start to goal confined to
the route's regions and ``rings`` rings of their neighbours (plus cells that became passable
since the build, inside the bounding box of those regions): Dijkstra with Dial's buckets,
stopped once the goal is settled (a bucket queue costs ~0.02 us per cell where a heap A*
costs ~0.5 us per expansion, and the octile heuristic prunes little in a winding corridor).
The corridor's cells come from the map's per-region cell lists, and the search arrays are
per-thread buffers stamped per query, so a query touches only the corridor, never a
map-sized array. Every cell of the path is passable in the mask given.
"""

from __future__ import annotations

import threading

import numpy as np
from numba import njit
from numpy.typing import NDArray

from mresim_phys.planning.grid import DIAGONAL, MOVES, NO_PRED, STRAIGHT, passes_corner, walk_back
from mresim_phys.planning.topoanchor import Anchor
from mresim_phys.planning.topomap import TopologicalMap
from mresim_phys.types import BoolGrid, FloatArray

# The corridor search's order of MOVES: the four straight ones (up, down, left, right), then
# up-left, up-right, down-left, down-right. The order decides ties between equal paths.
_STEPS = tuple(MOVES[k] for k in (1, 6, 3, 4, 0, 2, 5, 7))


@njit(cache=True, nogil=True)
def _corridor(
    indptr: NDArray[np.int32],
    indices: NDArray[np.int32],
    boxes: NDArray[np.int64],
    route: NDArray[np.int64],
    rings: int,
    ends: NDArray[np.int64],
) -> tuple[NDArray[np.bool_], NDArray[np.int64]]:
    """The corridor: the route's nodes and every node within ``rings`` graph edges of them
    (a mask over the nodes), and the bounding box of their regions and of the ``ends``'
    anchor boxes (half-open row0, row1, col0, col1)."""
    member = np.zeros(len(indptr) - 1, dtype=np.bool_)
    member[route] = True
    layer = route
    for _ in range(rings):
        grown = np.empty(len(member), dtype=np.int64)
        count = 0
        for u in layer:
            for k in range(indptr[u], indptr[u + 1]):
                v = indices[k]
                if not member[v]:
                    member[v] = True
                    grown[count] = v
                    count += 1
        layer = grown[:count]
    box = np.empty(4, dtype=np.int64)
    box[0], box[1] = ends[:, 0].min(), ends[:, 1].max()
    box[2], box[3] = ends[:, 2].min(), ends[:, 3].max()
    for node in range(len(member)):
        if member[node]:
            box[0], box[1] = min(box[0], boxes[node, 0]), max(box[1], boxes[node, 1])
            box[2], box[3] = min(box[2], boxes[node, 2]), max(box[3], boxes[node, 3])
    return member, box


@njit(cache=True, nogil=True)
def _search_to(
    pad: NDArray[np.bool_],
    wp: int,
    corridor: tuple[NDArray[np.int32], NDArray[np.int64], NDArray[np.bool_], NDArray[np.int64]],
    ends: tuple[int, int],
    work: tuple[FloatArray, NDArray[np.int32], NDArray[np.int32]],
    mark: int,
) -> float:
    """Dijkstra with Dial's bucket ring (as ``planning._dijkstra``) from ``ends[0]`` to
    ``ends[1]``, confined to the corridor, stopped once the target is settled.

    Cells are flat indices of the padded grid (row width ``wp``); ``pad`` is passability
    now. The corridor is ``(cells, starts, member, extra)``: the cells of each region
    ``k`` with ``member[k]`` (``cells[starts[k]:starts[k + 1]]``) that are passable now,
    and the ``extra`` cells (passable now, in no region). A diagonal move is forbidden when
    both cells beside it are impassable, as on the grid: a cell of a region outside the
    corridor still lets a diagonal past it.

    ``work`` is ``(state, pred, ring)``, reused between queries. ``state[v]`` is
    (mark, cost): a cell belongs to this query's corridor when its mark is ``mark``, and
    only the corridor's cells are reset, so a query never pays for a map-sized fill (the
    mark and the cost share a cache line). ``ring`` (3, n) holds the bands. Returns the
    target's cost (inf if unreachable; ``pred`` then leads back from it to the source),
    or -1 when a band outgrew the ring (the caller retries with a wider one).
    """
    cells, starts, member, extra = corridor
    state, pred, ring = work
    source, target = ends
    key = float(mark)
    for node in range(len(member)):
        if member[node]:
            for k in range(starts[node], starts[node + 1]):
                if pad[cells[k]]:
                    state[cells[k], 0], state[cells[k], 1] = key, np.inf
    for v in extra:
        state[v, 0], state[v, 1] = key, np.inf
    if state[source, 0] != key or state[target, 0] != key:
        return np.inf
    state[source, 1], pred[source], ring[0, 0] = 0.0, NO_PRED, source
    sizes = np.array([1, 0, 0])
    band, now, next1, next2 = 0, 0, 1, 2  # ring rows of bands band, band + 1, band + 2
    while sizes[now] + sizes[next1] > 0 and state[target, 1] >= band:
        for j in range(sizes[now]):
            u = ring[now, j]
            here = state[u, 1]
            if int(here) != band:
                continue  # queued again in a lower band since
            # the corner rule on the four straight neighbours, each read once
            up, down, left, right = pad[u - wp], pad[u + wp], pad[u - 1], pad[u + 1]
            for k in range(8):  # unrolled by the compiler
                v = u + _STEPS[k][0] * wp + _STEPS[k][1]
                if k < 4:
                    cost = here + STRAIGHT
                else:
                    cost = here + DIAGONAL
                    if not passes_corner(up if k < 6 else down, left if k % 2 == 0 else right):
                        continue
                if state[v, 0] != key:
                    continue
                old = state[v, 1]
                if cost >= old:
                    continue
                state[v, 1], pred[v] = cost, u
                band_v = int(cost)
                if old == np.inf or int(old) != band_v:  # else it waits in band_v already
                    row = next1 if band_v == band + 1 else next2
                    if sizes[row] == ring.shape[1]:
                        return -1.0
                    ring[row, sizes[row]] = v
                    sizes[row] += 1
        sizes[now] = 0
        band, now, next1, next2 = band + 1, next1, next2, now
    found: float = state[target, 1]
    return found


@njit(cache=True, nogil=True)
def _unlabelled(
    passable: NDArray[np.bool_], labels: NDArray[np.int32], box: NDArray[np.int64]
) -> NDArray[np.int64]:
    """Flat padded-grid indices of the cells in ``box`` that are passable but in no region."""
    wp, count = passable.shape[1] + 2, 0
    for r in range(box[0], box[1]):
        for c in range(box[2], box[3]):
            count += passable[r, c] and labels[r, c] < 0
    out = np.empty(count, dtype=np.int64)
    count = 0
    if len(out):
        for r in range(box[0], box[1]):
            for c in range(box[2], box[3]):
                if passable[r, c] and labels[r, c] < 0:
                    out[count], count = (r + 1) * wp + c + 1, count + 1
    return out


class _Work(threading.local):
    """Per-thread search arrays over the padded grid, reused by every query (see
    :func:`_search_to`): allocating and filling them per query would cost about as much
    as the search itself on an 800x600 map."""

    def __init__(self) -> None:
        self.mark = 0
        self.state = np.zeros((0, 2))
        self.pred = np.empty(0, dtype=np.int32)
        self.ring = np.empty((3, 1024), dtype=np.int32)
        self.pad = np.zeros((0, 0), dtype=np.bool_)

    def arrays(self, size: int) -> tuple[FloatArray, NDArray[np.int32], NDArray[np.int32]]:
        """``(state, pred, ring)`` for ``size`` cells; a fresh mark is in ``self.mark``."""
        if size > len(self.pred):
            self.state, self.pred = np.zeros((size, 2)), np.empty(size, dtype=np.int32)
            self.mark = 0
        self.mark += 1
        return self.state, self.pred, self.ring

    def widen_ring(self) -> None:
        """Twice as many cells per band."""
        self.ring = np.empty((3, 2 * self.ring.shape[1]), dtype=np.int32)

    def padded(self, passable: BoolGrid) -> NDArray[np.bool_]:
        """``passable`` with a blocked border, flat (a reused buffer)."""
        shape = (passable.shape[0] + 2, passable.shape[1] + 2)
        if self.pad.shape != shape:
            self.pad = np.zeros(shape, dtype=np.bool_)
        self.pad[1:-1, 1:-1] = passable
        return self.pad.ravel()


_WORK = _Work()


def corridor_path(
    topo: TopologicalMap,
    passable: BoolGrid,
    ends: tuple[tuple[int, int], tuple[int, int]],
    route: NDArray[np.int64],
    rings: int,
    anchors: tuple[Anchor, Anchor],
    fresh: bool,
) -> FloatArray:
    """Shortest path confined to the regions of ``route`` and ``rings`` rings of their
    neighbours, and to cells no region holds; (0, 2) if the corridor does not join the
    ends. ``fresh``: ``passable`` is the mask the map was built from."""
    graph, grid = topo.graph, topo.search_grid
    member, box = _corridor(
        graph.indptr, graph.indices, topo.boxes, route, rings,
        np.array((anchors[0].box, anchors[1].box), dtype=np.int64),
    )  # fmt: skip
    wp = grid.wp
    if fresh:
        pad, extra = grid.passable, np.zeros(0, dtype=np.int64)
    else:  # cells passable now that no region holds join the corridor inside its box
        pad = _WORK.padded(passable)
        extra = _unlabelled(np.ascontiguousarray(passable), topo.labels, box)
    ends_flat = ((ends[0][0] + 1) * wp + ends[0][1] + 1, (ends[1][0] + 1) * wp + ends[1][1] + 1)
    corridor = (grid.cells, grid.starts, member, extra)
    cost = -1.0
    while cost < 0:
        work = _WORK.arrays(pad.size)
        cost = _search_to(pad, wp, corridor, ends_flat, work, _WORK.mark)
        if cost < 0:
            _WORK.widen_ring()
    if not np.isfinite(cost):
        return np.zeros((0, 2))
    rows, cols = np.divmod(walk_back(work[1], ends_flat[1]), wp)
    return np.column_stack((cols - 0.5, rows - 0.5))
