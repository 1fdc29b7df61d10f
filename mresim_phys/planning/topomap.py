"""Planning (phase 4b): the topological map, what it holds and the queries it answers.

A :class:`TopologicalMap` is the skeleton of one passable mask as a graph of node regions:
its nodes (skeleton cells), the region (nearest node along passable space) of every
passable cell, the graph of adjacent regions with the cost of a real path between their
nodes, and each region's box and cells. It answers graph queries (``route``, ``widen``,
``adjacency``, ``junctions``) and hands the corridor search its padded grid and per-region
cell lists (``search_grid``).

Building one is :mod:`mresim_phys.planning.topobuild`; sharing builds between robots is
:mod:`mresim_phys.planning.topocache`. Typical use (both names are in
:mod:`mresim_phys.planning`): ``topo = shared_map(passable, spacing=10)``;
``nodes, cost = topo.route(a, b)``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray
from scipy.ndimage import convolve
from scipy.sparse import csr_matrix

from mresim_phys.types import BoolGrid, IntArray


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
