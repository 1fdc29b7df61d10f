"""Planning (phase 4b): where a topological query's ends join the node graph.

The first step of a ``topological`` query (:mod:`mresim_phys.planning.topological`): each end
of the path joins the graph at a node, the region of its own cell, or, for a cell that
became passable after the map was built (in no region), the region of the nearest labelled
cell, found by a small breadth-first grid search within ``ANCHOR_REACH`` node spacings.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray

from mresim_phys.planning.grid import MOVES, Box, Window, diagonal_ok
from mresim_phys.planning.topomap import TopologicalMap
from mresim_phys.types import BoolGrid

ANCHOR_REACH = 2  # node spacings: how far an unlabelled end may be from a labelled cell


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
