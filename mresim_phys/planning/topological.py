"""Planning (phase 4b): the ``topological`` planner, a route over the skeleton's node regions.

The robot keeps a :class:`~mresim_phys.planning.topomap.TopologicalMap` of its passable
cells and rebuilds it only when enough of them changed (``rebuild_fraction`` of the cells
it was built from); builds come from a content-addressed cache shared by every planner
(:mod:`mresim_phys.planning.topocache`), so robots holding the same map (after an exchange)
build it once. A query:

1. anchors each end to a node: the region of its cell, or (a cell that became passable
   after the build) the region of the nearest labelled cell, found by a small grid search
   (:mod:`mresim_phys.planning.topoanchor`);
2. finds the cheapest node route on the region graph (``TopologicalMap.route``: Dijkstra on
   its CSR arrays, numba);
3. searches the grid from start to goal confined to the route's regions and ``corridor``
   rings of their neighbours (plus cells that became passable since the build, inside
   the bounding box of those regions): Dijkstra with Dial's buckets, stopped once the goal
   is settled, touching only the corridor, never a map-sized array
   (:mod:`mresim_phys.planning.topocorridor`).

Every cell of the path is passable NOW (the mask given, not the one the map was built
from), so a path never crosses an obstacle or an unknown cell; when the map is too stale to
route (no route, or the corridor is cut), the planner falls back to plain grid A*. Paths are
optimal within the corridor, hence at most slightly longer than ``astar``'s.

Terrain: the region graph and the corridor search are uniform-cost, so with known slow
terrain (a ``slowness`` grid, ``planning.costs``) a query is planned by cost-aware grid
A* over the whole passable window instead (the map is still kept up to date for the
strategies' junctions and the skeleton layer).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np
from numba import njit
from numpy.typing import NDArray

from mresim_phys.planning.astar import astar_search, weighted_astar
from mresim_phys.planning.base import GridPlanner
from mresim_phys.planning.catalog import PLANNERS
from mresim_phys.planning.grid import Window
from mresim_phys.planning.params import PlannerParams, TopologicalParams
from mresim_phys.planning.topoanchor import anchor
from mresim_phys.planning.topocache import SHARED, MapCache
from mresim_phys.planning.topocorridor import corridor_path
from mresim_phys.planning.topomap import TopologicalMap
from mresim_phys.types import BoolGrid, FloatArray


@njit(cache=True, nogil=True)
def _same(a: NDArray[np.bool_], b: NDArray[np.bool_]) -> bool:
    """Whether two flat masks are equal (no early exit: the loop vectorises)."""
    differ = False
    for i in range(a.size):
        differ |= a[i] != b[i]
    return not differ


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
        self,
        passable: BoolGrid,
        start: tuple[int, int],
        goal: tuple[int, int],
        slowness: FloatArray | None = None,
    ) -> FloatArray:
        """A cell-centre path through the node regions; (0, 2) if the goal is unreachable.
        With known slow terrain: cost-aware A* (see the module docstring)."""
        topo, fresh = self._refresh(passable)
        if slowness is not None:
            return weighted_astar(passable, start, goal, slowness)
        return topological_path(topo, passable, start, goal, self.params.corridor, fresh)

    def info(self) -> Mapping[str, Any]:
        """The skeleton of the map last planned on, for the renderer's skeleton layer."""
        return {"skeleton": self.map.skeleton} if self.map is not None else {}
