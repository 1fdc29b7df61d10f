"""Planning (phase 4b): building the topological map of a passable mask.

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

The result is a :class:`~mresim_phys.planning.topomap.TopologicalMap`. Planners and
strategies take builds from :mod:`mresim_phys.planning.topocache`, which builds a mask
once; ``build_map`` itself always builds.
"""

from __future__ import annotations

from typing import TypeVar

import numpy as np
from numba import njit
from numpy.typing import NDArray
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
from mresim_phys.planning.topomap import TopologicalMap
from mresim_phys.types import BoolGrid, IntArray

ScalarT = TypeVar("ScalarT", bound=np.generic)


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
