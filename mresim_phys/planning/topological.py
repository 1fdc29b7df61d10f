"""``topological``: a route over the skeleton's node regions, grid search inside (phase 4b).

The robot keeps a :class:`~mresim_phys.planning.topomap.TopologicalMap` of its passable
cells and rebuilds it only when enough of them changed (``rebuild_fraction`` of the cells
it was built from); builds come from a content-addressed cache shared by every planner,
so robots holding the same map (after an exchange) build it once. A query:

1. anchors each end to a node: the region of its cell, or (a cell that became passable
   after the build) the region of the nearest labelled cell, found by a small grid search;
2. finds the cheapest node route on the region graph (Dijkstra on its CSR arrays, numba);
3. searches the grid from start to goal confined to the route's regions and ``corridor``
   rings of their neighbours (plus cells that became passable since the build, inside
   the bounding box of those regions): Dijkstra with Dial's buckets, stopped once the goal
   is settled (a bucket queue costs ~0.02 us per cell where a heap A* costs ~0.5 us per
   expansion, and the octile heuristic prunes little in a winding corridor). The corridor's
   cells come from the map's per-region cell lists, and the search arrays are per-thread
   buffers stamped per query, so a query touches only the corridor, never a map-sized array.

Every cell of the path is passable NOW (the mask given, not the one the map was built
from), so a path never crosses an obstacle or an unknown cell; when the map is too stale to
route (no route, or the corridor is cut), the planner falls back to plain grid A*. Paths are
optimal within the corridor, hence at most slightly longer than ``astar``'s.
"""

from __future__ import annotations

import threading
from collections.abc import Mapping
from typing import Any, ClassVar, NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray
from pydantic import Field

from mresim_phys.planning.astar import astar_search
from mresim_phys.planning.base import PLANNERS, GridPlanner, PlannerParams
from mresim_phys.planning.grid import (
    DIAGONAL,
    MOVES,
    NO_PRED,
    STRAIGHT,
    Box,
    Window,
    diagonal_ok,
    passes_corner,
    walk_back,
)
from mresim_phys.planning.topomap import SHARED, MapCache, TopologicalMap
from mresim_phys.types import BoolGrid, FloatArray

# The corridor search's order of MOVES: the four straight ones (up, down, left, right), then
# up-left, up-right, down-left, down-right. The order decides ties between equal paths.
_STEPS = tuple(MOVES[k] for k in (1, 6, 3, 4, 0, 2, 5, 7))
ANCHOR_REACH = 2  # node spacings: how far an unlabelled end may be from a labelled cell


class TopologicalParams(PlannerParams):
    """Parameters of the topological planner."""

    node_spacing: int = Field(
        10, ge=2, le=200, description="Skeleton node spacing: one node per block of this size."
    )
    rebuild_fraction: float = Field(
        0.05,
        ge=0,
        le=1,
        description="Rebuild when this fraction of the built map's passable cells changed.",
    )
    corridor: int = Field(
        1,
        ge=0,
        le=5,
        description="Rings of neighbouring regions searched besides the route's (0 = none).",
    )


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


@njit(cache=True, nogil=True)
def _same(a: NDArray[np.bool_], b: NDArray[np.bool_]) -> bool:
    """Whether two flat masks are equal (no early exit: the loop vectorises)."""
    differ = False
    for i in range(a.size):
        differ |= a[i] != b[i]
    return not differ


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


@njit(cache=True, nogil=True)
def _nearest_labelled(
    pad: NDArray[np.bool_], labels: NDArray[np.int32], wp: int, source: int
) -> int:
    """Breadth-first search (move rules) from ``source`` to the first labelled cell; -1 if none."""
    seen = np.zeros(pad.size, dtype=np.bool_)
    queue = np.empty(pad.size, dtype=np.int64)
    queue[0], seen[source], head, tail = source, True, 0, 1
    while head < tail:
        u: int = queue[head]
        head += 1
        if labels[u] >= 0:
            return u
        for dr, dc in MOVES:
            v = u + dr * wp + dc
            if seen[v] or not pad[v]:
                continue
            if dr != 0 and dc != 0 and not diagonal_ok(pad, wp, u, dr, dc):
                continue
            seen[v] = True
            queue[tail], tail = v, tail + 1
    return -1


def _labels_in(topo: TopologicalMap, box: Box) -> NDArray[np.int32]:
    """Flat padded window of region labels over ``box`` (-1 on the border)."""
    r0, r1, c0, c1 = box
    out = np.full((r1 - r0 + 2, c1 - c0 + 2), -1, dtype=np.int32)
    out[1:-1, 1:-1] = topo.labels[r0:r1, c0:c1]
    return out.ravel()


def _around(cell: tuple[int, int], reach: int, shape: tuple[int, ...]) -> Box:
    r, c = cell
    return (max(r - reach, 0), min(r + reach + 1, shape[0]),
            max(c - reach, 0), min(c + reach + 1, shape[1]))  # fmt: skip


class Anchor(NamedTuple):
    """Where a path end joins the graph: a node, and the box its way there lies in."""

    node: int
    box: Box


def anchor(topo: TopologicalMap, passable: BoolGrid, cell: tuple[int, int]) -> Anchor | None:
    """The node a path end joins the graph at: its region's, or the nearest labelled cell's."""
    own = int(topo.labels[cell])
    if own >= 0:
        return Anchor(own, (cell[0], cell[0] + 1, cell[1], cell[1] + 1))
    box = _around(cell, ANCHOR_REACH * topo.spacing, passable.shape)
    window = Window.around(passable, box)
    found = _nearest_labelled(window.pad, _labels_in(topo, box), window.wp, window.node(cell))
    if found < 0:
        return None
    row, col = divmod(found, window.wp)
    return Anchor(int(topo.labels[row + window.origin[0], col + window.origin[1]]), box)


def topological_path(
    topo: TopologicalMap,
    passable: BoolGrid,
    start: tuple[int, int],
    goal: tuple[int, int],
    rings: int = 1,
    fresh: bool | None = None,
) -> FloatArray:
    """Cell-centre path over the route's regions (see the module docstring); (0, 2) if none.

    ``rings`` rings of neighbouring regions widen the corridor around the route. ``fresh``
    says the map was built from ``passable`` itself: its graph then knows connectivity
    exactly (regions cover every passable cell, edges every legal move between regions),
    so no route means no path, without the grid A* fallback. None: compare the masks.
    """
    if fresh is None:
        fresh = passable.shape == topo.passable.shape and _same(
            np.ascontiguousarray(passable).ravel(), topo.passable.ravel()
        )
    first, last = anchor(topo, passable, start), anchor(topo, passable, goal)
    if first is not None and last is not None:
        route, _ = topo.route(first.node, last.node)
        if fresh and not len(route):
            return np.zeros((0, 2))
        if len(route):
            path = corridor_path(topo, passable, (start, goal), route, rings, (first, last), fresh)
            if len(path):
                return path
    window = Window.of(passable)
    assert window is not None  # the start is passable
    return astar_search(window, start, goal)[0]


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


@PLANNERS.register
class TopologicalPlanner(GridPlanner):
    """Route over the skeleton's node regions, then the shortest grid path inside them."""

    name = "topological"

    Params: ClassVar[type[PlannerParams]] = TopologicalParams

    def __init__(self, params: TopologicalParams, cache: MapCache = SHARED) -> None:
        super().__init__(params)
        self.params: TopologicalParams = params
        self.cache = cache
        self.map: TopologicalMap | None = None

    def current_map(self, passable: BoolGrid) -> TopologicalMap:
        """The map to plan on: the last one, or a rebuild if ``passable`` changed enough."""
        return self._refresh(passable)[0]

    def _refresh(self, passable: BoolGrid) -> tuple[TopologicalMap, bool]:
        """The map to plan on, and whether it was built from ``passable`` itself."""
        topo = self.map
        if topo is not None and topo.passable.shape == passable.shape:
            changed = np.count_nonzero(topo.passable != passable)
            if changed <= self.params.rebuild_fraction * np.count_nonzero(topo.passable):
                return topo, changed == 0
        self.map = self.cache.get(passable, self.params.node_spacing)
        return self.map, True

    def search(
        self, passable: BoolGrid, start: tuple[int, int], goal: tuple[int, int]
    ) -> FloatArray:
        """A cell-centre path through the node regions; (0, 2) if the goal is unreachable."""
        topo, fresh = self._refresh(passable)
        return topological_path(topo, passable, start, goal, self.params.corridor, fresh)

    def info(self) -> Mapping[str, Any]:
        """The skeleton of the map last planned on, for the renderer's skeleton layer."""
        return {"skeleton": self.map.skeleton} if self.map is not None else {}
