"""Topological map (phase 4b): the skeleton of passable space as a graph of node regions.

Built from a configuration-space mask (the cells a robot centre may occupy):

1. skeleton: Zhang-Suen thinning of the passable cells (their medial lines; a numba kernel,
   :mod:`mresim_phys.planning.skeleton`, several times faster than scikit-image's);
2. nodes: skeleton cells sampled uniformly, one per ``spacing`` x ``spacing`` block (the
   skeleton cell nearest the block centre);
3. regions: every passable cell belongs to its nearest node ALONG passable space, by one
   multi-source Dijkstra (numba, Dial's buckets, the move rule of
   :mod:`mresim_phys.planning.grid`). A wall is never crossed, so two rooms separated by a wall
   never share a region, and each region is connected. Cells no node reaches (a passable
   pocket the skeleton missed) get nodes of their own;
4. graph: two regions are adjacent when a legal move joins them; the edge costs the
   shortest such crossing, ``d(u) + move + d(v)`` (each ``d`` the cell's path cost to
   its own node), i.e. the length of a real path between the two nodes.

Maps are content-addressed: ``shared_map`` returns the one build of an identical mask
and spacing, so robots whose maps were merged (or the base station's) reuse one build.

Typical use: ``topo = shared_map(passable, spacing=10)``; ``nodes, cost = topo.route(a, b)``.
"""

from __future__ import annotations

import hashlib
from collections import OrderedDict
from dataclasses import dataclass, field
from functools import cached_property
from typing import NamedTuple, TypeVar

import numpy as np
from numba import njit
from numpy.typing import NDArray
from scipy.ndimage import convolve
from scipy.sparse import csr_matrix

from mresim_phys.planning.grid import (
    DIAGONAL,
    FORWARD_MOVES,
    MOVES,
    STRAIGHT,
    Window,
    bbox,
    diagonal_ok,
)
from mresim_phys.planning.skeleton import thin
from mresim_phys.types import BoolGrid, IntArray

ScalarT = TypeVar("ScalarT", bound=np.generic)
CACHE_SIZE = 8  # maps kept by shared_map: a team's distinct maps at one time, roughly


@njit(cache=True, nogil=True)
def _assign(
    pad: NDArray[np.bool_], wp: int, seeds: NDArray[np.int64]
) -> tuple[NDArray[np.int32], NDArray[np.float64]]:
    """Label of each cell's nearest seed along passable cells, and the path cost to it.

    Multi-source Dijkstra with Dial's bucket ring, as ``planning._dijkstra``: every
    seed starts at cost 0 with its own label, and a cell takes the label of the
    neighbour it was reached from.
    """
    dist = np.full(pad.size, np.inf)
    label = np.full(pad.size, -1, dtype=np.int32)
    queued = np.full(pad.size, -1, dtype=np.int32)
    width = max(int(np.count_nonzero(pad)), len(seeds))
    ring = np.empty((3, width), dtype=np.int32)
    sizes = np.zeros(3, dtype=np.int64)
    for i in range(len(seeds)):
        s = seeds[i]
        dist[s], label[s], queued[s] = 0.0, i, 0
        ring[0, sizes[0]] = s
        sizes[0] += 1
    band = 0
    while sizes[band % 3] + sizes[(band + 1) % 3] > 0:
        slot = band % 3
        for j in range(sizes[slot]):
            u = ring[slot, j]
            here = dist[u]
            if int(here) != band:
                continue
            for dr, dc in MOVES:
                v = u + dr * wp + dc
                if not pad[v]:
                    continue
                if dr != 0 and dc != 0:
                    if not diagonal_ok(pad, wp, u, dr, dc):
                        continue
                    cost = here + DIAGONAL
                else:
                    cost = here + STRAIGHT
                if cost < dist[v]:
                    dist[v], label[v] = cost, label[u]
                    target = int(cost)
                    if queued[v] != target:
                        queued[v] = target
                        ring[target % 3, sizes[target % 3]] = v
                        sizes[target % 3] += 1
        sizes[slot] = 0
        band += 1
    return label, dist


@njit(cache=True, nogil=True)
def _adjacency(
    pad: NDArray[np.bool_],
    wp: int,
    label: NDArray[np.int32],
    dist: NDArray[np.float64],
    count: int,
    width: int,
) -> tuple[NDArray[np.int64], NDArray[np.float64], bool]:
    """For each region a, its adjacent regions b > a and the cheapest crossing a -> b.

    Row ``a`` of the tables holds up to ``width`` neighbours (-1 = empty slot); the flag
    is False when some region has more, and the caller retries with wider tables. A
    crossing is a legal move u -> v between the regions; it costs d(u) + move + d(v).
    """
    other = np.full((count, width), -1, dtype=np.int64)
    cost = np.full((count, width), np.inf)
    for u in range(pad.size):
        lu = label[u]
        if lu < 0:
            continue
        for dr, dc in FORWARD_MOVES:
            v = u + dr * wp + dc
            lv = label[v]
            if lv < 0 or lv == lu:
                continue
            step = STRAIGHT
            if dr != 0 and dc != 0:
                if not diagonal_ok(pad, wp, u, dr, dc):
                    continue
                step = DIAGONAL
            a, b = min(lu, lv), max(lu, lv)
            c = dist[u] + step + dist[v]
            for k in range(width + 1):
                if k == width:
                    return other, cost, False
                if other[a, k] == b or other[a, k] < 0:
                    other[a, k] = b
                    cost[a, k] = min(cost[a, k], c)
                    break
    return other, cost, True


@njit(cache=True, nogil=True)
def _region_boxes(label: NDArray[np.int32], wp: int, count: int) -> NDArray[np.int64]:
    """Half-open window box (row0, row1, col0, col1) of each region."""
    boxes = np.empty((count, 4), dtype=np.int64)
    boxes[:, 0] = boxes[:, 2] = np.iinfo(np.int64).max
    boxes[:, 1] = boxes[:, 3] = -1
    for u in range(label.size):
        k = label[u]
        if k >= 0:
            r, c = u // wp, u % wp
            boxes[k, 0], boxes[k, 1] = min(boxes[k, 0], r), max(boxes[k, 1], r + 1)
            boxes[k, 2], boxes[k, 3] = min(boxes[k, 2], c), max(boxes[k, 3], c + 1)
    return boxes


@njit(cache=True, nogil=True)
def _region_cells(
    label: NDArray[np.int32], count: int
) -> tuple[NDArray[np.int32], NDArray[np.int64]]:
    """Cells of each region, by a counting sort: region ``k`` holds the flat indices
    ``cells[starts[k]:starts[k + 1]]``, in increasing order."""
    starts = np.zeros(count + 1, dtype=np.int64)
    for u in range(label.size):
        if label[u] >= 0:
            starts[label[u] + 1] += 1
    for k in range(count):
        starts[k + 1] += starts[k]
    cells = np.empty(starts[count], dtype=np.int32)
    fill = starts[:count].copy()
    for u in range(label.size):
        k = label[u]
        if k >= 0:
            cells[fill[k]] = u
            fill[k] += 1
    return cells, starts


class SearchGrid(NamedTuple):
    """What a corridor search needs, precomputed at build: the grid padded by one blocked
    cell on every side and flattened (row width ``wp``), the mask the map was built from on
    it, and the cells of each region (``cells[starts[k]:starts[k + 1]]``, flat padded
    indices)."""

    wp: int
    passable: NDArray[np.bool_]
    cells: NDArray[np.int32]
    starts: NDArray[np.int64]


def sample_nodes(cells_rc: IntArray, spacing: int) -> IntArray:
    """One cell per ``spacing`` x ``spacing`` block: the one nearest the block centre.

    >>> sample_nodes(np.array([[0, 0], [1, 1], [0, 5], [4, 4]]), 4).tolist()
    [[1, 1], [0, 5], [4, 4]]
    """
    if len(cells_rc) == 0:
        return np.zeros((0, 2), dtype=np.int64)
    blocks = cells_rc // spacing
    centre = blocks * spacing + (spacing - 1) / 2.0
    gap = ((cells_rc - centre) ** 2).sum(axis=1)
    key = blocks[:, 0] * (int(blocks[:, 1].max()) + 1) + blocks[:, 1]
    order = np.lexsort((cells_rc[:, 1], cells_rc[:, 0], gap, key))
    first = np.ones(len(order), dtype=bool)
    first[1:] = key[order][1:] != key[order][:-1]
    return cells_rc[order[first]]


@dataclass(frozen=True, eq=False)
class TopologicalMap:
    """Skeleton, nodes, node regions and node graph of one passable mask.

    Attributes:
        passable: The mask the map was built from (read-only).
        skeleton: Skeleton cells (bool grid, full size).
        nodes_rc: (k, 2) node cells (row, col).
        labels: Region (node index) of every cell, -1 where not passable (full size).
        graph: Symmetric (k, k) CSR matrix of edge costs between adjacent regions.
        boxes: (k, 4) half-open full-grid box (row0, row1, col0, col1) of each region.
        spacing: Node spacing (cells) used to sample the skeleton.
    """

    passable: BoolGrid
    skeleton: BoolGrid
    nodes_rc: IntArray
    labels: NDArray[np.int32] = field(repr=False)
    graph: csr_matrix = field(repr=False)
    boxes: IntArray = field(repr=False)
    spacing: int = 10

    @property
    def node_count(self) -> int:
        """Number of nodes (and regions)."""
        return len(self.nodes_rc)

    @cached_property
    def search_grid(self) -> SearchGrid:
        """The padded grid and region cell lists for corridor searches (made at build)."""
        rows, cols = self.passable.shape
        label = np.full((rows + 2, cols + 2), -1, dtype=np.int32)
        label[1:-1, 1:-1] = self.labels
        cells, starts = _region_cells(label.ravel(), self.node_count)
        pad = np.zeros((rows + 2, cols + 2), dtype=np.bool_)
        pad[1:-1, 1:-1] = self.passable
        return SearchGrid(cols + 2, pad.ravel(), cells, starts)

    @cached_property
    def adjacency(self) -> csr_matrix:
        """Boolean (k, k) node adjacency."""
        adjacency: csr_matrix = self.graph.astype(bool)
        return adjacency

    @cached_property
    def junctions(self) -> IntArray:
        """(m, 2) skeleton cells with three or more skeleton neighbours (branch points)."""
        sk = self.skeleton.view(np.uint8)
        neighbours = convolve(sk, np.ones((3, 3), dtype=np.uint8), mode="constant") - sk
        return np.argwhere(self.skeleton & (neighbours >= 3))

    def widen(self, nodes: IntArray, rings: int) -> IntArray:
        """``nodes`` and every node within ``rings`` graph edges of them (sorted)."""
        member = np.zeros(self.node_count, dtype=bool)
        member[nodes] = True
        for _ in range(rings):
            member |= self.adjacency @ member
        return np.flatnonzero(member)

    def route(self, a: int, b: int) -> tuple[IntArray, float]:
        """Cheapest graph route from node ``a`` to node ``b`` (node indices) and its cost.

        The cost is the length of a real path between the two nodes (each edge is one).
        No route: an empty array and inf.
        """
        nodes, cost = _graph_route(self.graph.indptr, self.graph.indices, self.graph.data, a, b)
        return nodes, cost


@njit(cache=True, nogil=True)
def _graph_route(
    indptr: NDArray[np.int32],
    indices: NDArray[np.int32],
    costs: NDArray[np.float64],
    a: int,
    b: int,
) -> tuple[NDArray[np.int64], float]:
    """Dijkstra (an inline binary heap) on a CSR graph from ``a``, stopped once ``b`` is settled:
    the route's nodes from ``a`` to ``b`` and its cost (empty and inf if there is none)."""
    count = len(indptr) - 1
    dist = np.full(count, np.inf)
    pred = np.full(count, -1, dtype=np.int64)
    done = np.zeros(count, dtype=np.bool_)
    keys = np.empty(len(indices) + 1)  # a binary heap of (cost, node), one entry per push
    items = np.empty(len(indices) + 1, dtype=np.int64)
    keys[0], items[0], dist[a], size = 0.0, a, 0.0, 1
    while size > 0:
        u, size = items[0], size - 1
        key, item, i = keys[size], items[size], 0
        while 2 * i + 1 < size:  # sift the last entry down from the root
            child = 2 * i + 1
            if child + 1 < size and keys[child + 1] < keys[child]:
                child += 1
            if keys[child] >= key:
                break
            keys[i], items[i], i = keys[child], items[child], child
        keys[i], items[i] = key, item
        if done[u]:
            continue
        done[u] = True
        if u == b:
            break
        for k in range(indptr[u], indptr[u + 1]):
            v, cost = indices[k], dist[u] + costs[k]
            if cost < dist[v]:
                dist[v], pred[v], i = cost, u, size
                size += 1
                while i > 0 and keys[(i - 1) >> 1] > cost:  # sift up
                    keys[i], items[i], i = keys[(i - 1) >> 1], items[(i - 1) >> 1], (i - 1) >> 1
                keys[i], items[i] = cost, v
    if not done[b]:
        return np.zeros(0, dtype=np.int64), np.inf
    length, node = 1, b
    while node != a:
        node, length = pred[node], length + 1
    nodes = np.empty(length, dtype=np.int64)
    node = b
    for i in range(length - 1, -1, -1):
        nodes[i], node = node, pred[node]
    return nodes, dist[b]


def build_map(passable: BoolGrid, spacing: int) -> TopologicalMap:
    """Build the topological map of ``passable`` (see the module docstring)."""
    shape = passable.shape
    frozen = passable.copy()
    frozen.flags.writeable = False
    box = bbox(passable)
    if box is None:
        return _empty_map(frozen, spacing)
    window = Window.around(passable, box)
    skeleton = np.zeros(shape, dtype=bool)
    skeleton[box[0] : box[1], box[2] : box[3]] = thin(passable[box[0] : box[1], box[2] : box[3]])
    nodes = sample_nodes(np.argwhere(skeleton), spacing)
    label, dist = _assign(window.pad, window.wp, _flat(window, nodes))
    while True:  # passable pockets the skeleton missed get nodes of their own
        missed = np.flatnonzero(window.pad & (label < 0))
        if len(missed) == 0:
            break
        missed_rc: IntArray = np.column_stack(np.divmod(missed, window.wp))
        extra = sample_nodes(missed_rc + window.origin, spacing)
        nodes = np.concatenate((nodes, extra))
        label, dist = _assign(window.pad, window.wp, _flat(window, nodes))
    graph = _graph(window, label, dist, len(nodes))
    boxes = _region_boxes(label, window.wp, len(nodes))
    boxes += np.repeat(window.origin, 2)
    labels = _full(window, label, shape, -1)
    topo = TopologicalMap(frozen, skeleton, nodes, labels, graph, boxes, spacing)
    _ = topo.search_grid  # made now: a rebuild, not the first query, pays for it
    return topo


def _flat(window: Window, nodes_rc: IntArray) -> NDArray[np.int64]:
    """Flat window indices of full-grid cells."""
    return (nodes_rc[:, 0] - window.origin[0]) * window.wp + (nodes_rc[:, 1] - window.origin[1])


def _full(
    window: Window, flat: NDArray[ScalarT], shape: tuple[int, ...], fill: float
) -> NDArray[ScalarT]:
    """A padded window array put back on the full grid (``fill`` outside)."""
    out = np.full(shape, fill, dtype=flat.dtype)
    padded = flat.reshape(-1, window.wp)[1:-1, 1:-1]
    r0, c0 = window.origin[0] + 1, window.origin[1] + 1
    out[r0 : r0 + padded.shape[0], c0 : c0 + padded.shape[1]] = padded
    return out


def _graph(
    window: Window, label: NDArray[np.int32], dist: NDArray[np.float64], count: int
) -> csr_matrix:
    """Node graph: the cheapest crossing between each pair of adjacent regions."""
    width, done = 16, False
    while not done:
        other, cost, done = _adjacency(window.pad, window.wp, label, dist, count, width)
        width *= 2
    a, k = np.nonzero(other >= 0)
    b, c = other[a, k], cost[a, k]
    rows, cols = np.concatenate((a, b)), np.concatenate((b, a))
    return csr_matrix((np.concatenate((c, c)), (rows, cols)), shape=(count, count))


def _empty_map(passable: BoolGrid, spacing: int) -> TopologicalMap:
    shape = passable.shape
    return TopologicalMap(
        passable, np.zeros(shape, dtype=bool), np.zeros((0, 2), dtype=np.int64),
        np.full(shape, -1, dtype=np.int32), csr_matrix((0, 0)),
        np.zeros((0, 4), dtype=np.int64), spacing,
    )  # fmt: skip


def digest(passable: BoolGrid) -> bytes:
    """A content key for a mask (its shape and bits)."""
    h = hashlib.blake2b(np.packbits(passable).tobytes(), digest_size=16)
    h.update(np.asarray(passable.shape, dtype=np.int64).tobytes())
    return h.digest()


class MapCache:
    """The last few topological maps, keyed by (mask content, spacing)."""

    def __init__(self, capacity: int = CACHE_SIZE) -> None:
        self.capacity = capacity
        self.builds = 0  # how many maps this cache has built (for tests and benchmarks)
        self._maps: OrderedDict[tuple[bytes, int], TopologicalMap] = OrderedDict()

    def get(self, passable: BoolGrid, spacing: int) -> TopologicalMap:
        """The map of ``passable``: an earlier identical build, or a new one."""
        key = (digest(passable), spacing)
        found = self._maps.get(key)
        if found is None:
            found = build_map(passable, spacing)
            self.builds += 1
            self._maps[key] = found
            if len(self._maps) > self.capacity:
                self._maps.popitem(last=False)
        self._maps.move_to_end(key)
        return found


SHARED = MapCache()  # content-addressed, so any planner may take any entry


def shared_map(passable: BoolGrid, spacing: int) -> TopologicalMap:
    """The topological map of ``passable`` from the process-wide cache."""
    return SHARED.get(passable, spacing)
