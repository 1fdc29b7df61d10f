"""``topological``: a route over the skeleton's node regions, grid search inside (phase 4b).

The robot keeps a :class:`~mresim_phys.planners.topomap.TopologicalMap` of its passable
cells and rebuilds it only when enough of them changed (``rebuild_fraction`` of the cells
it was built from); builds come from a content-addressed cache shared by every planner,
so robots holding the same map (after an exchange) build it once. A query:

1. anchors each end to a node: the region of its cell, or (a cell that became passable
   after the build) the region of the nearest labelled cell, found by a small grid search;
2. finds the cheapest node route on the region graph (``scipy.sparse.csgraph``);
3. searches the grid from start to goal confined to the route's regions and ``corridor``
   rings of their neighbours (plus cells that became passable since the build), inside
   the bounding box of those regions: Dijkstra with Dial's buckets, stopped once the goal
   is settled (a bucket queue costs ~0.05 us per cell where a heap A* costs ~0.5 us per
   expansion, and the octile heuristic prunes little in a winding corridor).

Every cell of the path is passable NOW (the mask given, not the one the map was built
from), so a path never crosses an obstacle or an unknown cell; when the map is too stale to
route (no route, or the corridor is cut), the planner falls back to plain grid A*. Paths are
optimal within the corridor, hence at most slightly longer than ``astar``'s.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray
from pydantic import Field

from ..types import BoolGrid, FloatArray
from .astar import astar_search
from .base import PLANNERS, GridPlanner, PlannerParams
from .grid import NO_PRED, SQRT2, Window, walk_back
from .topomap import SHARED, MapCache, TopologicalMap

Box = tuple[int, int, int, int]
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
def _corridor_mask(
    passable: NDArray[np.bool_],
    labels: NDArray[np.int32],
    allowed: NDArray[np.bool_],
    box: tuple[int, int, int, int],
) -> NDArray[np.uint8]:
    """Flat padded window over ``box``: 2 = passable with an allowed label (may be entered),
    1 = passable only (counts for the corner rule), 0 = blocked."""
    r0, r1, c0, c1 = box
    wp = c1 - c0 + 2
    pad = np.zeros((r1 - r0 + 2) * wp, dtype=np.uint8)
    for r in range(r0, r1):
        base = (r - r0 + 1) * wp + 1 - c0
        for c in range(c0, c1):
            if passable[r, c]:
                pad[base + c] = 2 if allowed[labels[r, c] + 1] else 1
    return pad


@njit(cache=True, nogil=True)
def _search_to(
    pad: NDArray[np.uint8], wp: int, source: int, target: int
) -> tuple[float, NDArray[np.int32]]:
    """Dijkstra with Dial's bucket ring (as ``planning._dijkstra``), stopped at the target.

    Only cells marked 2 in ``pad`` are entered; a diagonal move is forbidden when both
    cells beside it are blocked (0), as on the grid: a cell of a region outside the
    corridor still lets a diagonal past it.

    The target's cost is final once its band is expanded. Returns that cost (inf if
    unreachable) and the predecessor array. A bucket queue costs ~0.05 us per cell, where
    a heap A* spends ~0.5 us per expansion: in a corridor of regions, where the octile
    heuristic prunes little, settling the corridor is faster than A*.
    """
    dist = np.full(pad.size, np.inf)
    pred = np.full(pad.size, NO_PRED, dtype=np.int32)
    queued = np.full(pad.size, -1, dtype=np.int32)
    ring = np.empty((3, max(np.count_nonzero(pad == 2), 1)), dtype=np.int32)
    sizes = np.zeros(3, dtype=np.int64)
    dist[source], queued[source] = 0.0, 0
    ring[0, 0], sizes[0] = source, 1
    band = 0
    while sizes[band % 3] + sizes[(band + 1) % 3] > 0 and dist[target] >= band:
        slot = band % 3
        for j in range(sizes[slot]):
            u = ring[slot, j]
            here = dist[u]
            if int(here) != band:
                continue
            for dr in range(-1, 2):
                for dc in range(-1, 2):
                    v = u + dr * wp + dc
                    if v == u or pad[v] != 2:
                        continue
                    if dr != 0 and dc != 0:
                        if pad[u + dr * wp] == 0 and pad[u + dc] == 0:
                            continue
                        cost = here + SQRT2
                    else:
                        cost = here + 1.0
                    if cost < dist[v]:
                        dist[v], pred[v] = cost, u
                        band_v = int(cost)
                        if queued[v] != band_v:
                            queued[v] = band_v
                            ring[band_v % 3, sizes[band_v % 3]] = v
                            sizes[band_v % 3] += 1
        sizes[slot] = 0
        band += 1
    return dist[target], pred


@njit(cache=True, nogil=True)
def _nearest_labelled(
    pad: NDArray[np.bool_], labels: NDArray[np.int32], wp: int, source: int
) -> int:
    """Breadth-first search (move rules) from ``source`` to the first labelled cell; -1 if none."""
    seen = np.zeros(pad.size, dtype=np.bool_)
    queue = np.empty(pad.size, dtype=np.int64)
    queue[0], seen[source], head, tail = source, True, 0, 1
    while head < tail:
        u = queue[head]
        head += 1
        if labels[u] >= 0:
            return u
        for dr in range(-1, 2):
            for dc in range(-1, 2):
                v = u + dr * wp + dc
                if seen[v] or not pad[v]:
                    continue
                if dr != 0 and dc != 0 and not (pad[u + dr * wp] or pad[u + dc]):
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
    fresh: bool = False,
) -> FloatArray:
    """Cell-centre path over the route's regions (see the module docstring); (0, 2) if none.

    ``rings`` rings of neighbouring regions widen the corridor around the route. ``fresh``
    says the map was built from ``passable`` itself: its graph then knows connectivity
    exactly (regions cover every passable cell, edges every legal move between regions),
    so no route means no path, without the grid A* fallback.
    """
    ends = anchor(topo, passable, start), anchor(topo, passable, goal)
    if ends[0] is not None and ends[1] is not None:
        route, _ = topo.route(ends[0].node, ends[1].node)
        if fresh and not len(route):
            return np.zeros((0, 2))
        if len(route):
            nodes = topo.widen(route, rings)
            path = corridor_path(topo, passable, (start, goal), nodes, (ends[0], ends[1]))
            if len(path):
                return path
    window = Window.of(passable)
    assert window is not None  # the start is passable
    return astar_search(window, start, goal)[0]


def corridor_path(
    topo: TopologicalMap,
    passable: BoolGrid,
    ends: tuple[tuple[int, int], tuple[int, int]],
    nodes: NDArray[np.int64],
    anchors: tuple[Anchor, Anchor],
) -> FloatArray:
    """Shortest path confined to the regions of ``nodes`` and to cells no region holds."""
    boxes = np.vstack((topo.boxes[nodes], anchors[0].box, anchors[1].box))
    box = (int(boxes[:, 0].min()), int(boxes[:, 1].max()),
           int(boxes[:, 2].min()), int(boxes[:, 3].max()))  # fmt: skip
    allowed = np.zeros(topo.node_count + 1, dtype=np.bool_)
    allowed[0] = True  # label -1: passable now, not when the map was built
    allowed[nodes + 1] = True
    pad = _corridor_mask(passable, topo.labels, allowed, box)
    window = Window(pad, box[3] - box[2] + 2, (box[0] - 1, box[2] - 1))
    target = window.node(ends[1])
    cost, pred = _search_to(pad, window.wp, window.node(ends[0]), target)
    if not np.isfinite(cost):
        return np.zeros((0, 2))
    return window.points(walk_back(pred, target))


@PLANNERS.register("topological")
class TopologicalPlanner(GridPlanner):
    """Route over the skeleton's node regions, then the shortest grid path inside them."""

    Params = TopologicalParams

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
