"""Frontier regions (phase 3b, knowledge): the seen-but-unvisited space behind each frontier.

The original MRESim's frontier is not a line of cells but a region: every cell its robot
has seen free but not from near by (free and not *safe*: no robot scanned it from within
10 % of its range), and the cells beside unknown ones, traced into polygons. A frontier's
weight in the utility ``area / d^4`` is the polygon's area, so a doorway with a long
corridor seen through it outweighs a shadow behind a chair that the robot has walked past
(the chair's shadow lies in safe space; the corridor does not).

:func:`region_sizes` gives each frontier cluster of ``knowledge.frontiers`` that weight on
the grid: the cells of the 8-connected component, of the FREE cells outside safe space and
the frontier cells themselves, that holds the cluster. Two clusters in one region share
its size. The region mask is built over the FREE cells' bounding box; then each region that
holds a cluster is flood-filled from the cluster's first cell (``cv2.floodFill``, 8-connected:
the same components as ``cv2.connectedComponentsWithStats``), so the regions no frontier
borders are never labelled (0.8 against 2.1 ms a call on the library at the original's
settings). Past ``LAST_MARK - 1`` regions (each fill marks its region with its own byte) the
whole box is labelled at once instead.
"""

from __future__ import annotations

import cv2
import numpy as np

from mresim_phys.knowledge.targets import Clusters
from mresim_phys.planning.grid import Box
from mresim_phys.types import FREE, BeliefGrid, BoolGrid, IntArray

LAST_MARK = 255  # a region filled marks its cells with a byte of its own: 2, 3, ... up to this


def region_sizes(frontiers: Clusters, belief: BeliefGrid, safe: BoolGrid, box: Box) -> IntArray:
    """Cells of the seen-but-unvisited region that holds each cluster (module docstring).

    ``box`` (row0, row1, col0, col1, half-open) holds every FREE cell of ``belief``.

    >>> from mresim_phys.knowledge.frontiers import find_frontiers
    >>> belief = np.full((5, 8), FREE, dtype=np.uint8)
    >>> belief[:, 7] = 0  # unknown beyond the last column
    >>> safe = np.zeros((5, 8), dtype=bool)
    >>> safe[:, :3] = True  # the robot scanned the left part from near by
    >>> int(region_sizes(find_frontiers(belief), belief, safe, (0, 5, 0, 7))[0])
    20
    """
    k = len(frontiers)
    if k == 0:
        return np.zeros(0, dtype=np.intp)
    r0, r1, c0, c1 = box
    region = ((belief[r0:r1, c0:c1] == FREE) & ~safe[r0:r1, c0:c1]).view(np.uint8)
    cells = frontiers.cells_rc
    region[cells[:, 0] - r0, cells[:, 1] - c0] = 1
    _, first = np.unique(frontiers.cluster_of, return_index=True)
    seeds = cells[first] - (r0, c0)
    sizes = np.zeros(len(seeds), dtype=np.intp)
    areas = [0, 0]  # the area of the region filled with each byte value from 2 on
    for i, (r, c) in enumerate(seeds.tolist()):
        mark = int(region[r, c])
        if mark < 2:  # a region not filled yet
            if len(areas) > LAST_MARK:
                return labelled_sizes(region, seeds)
            mark = len(areas)
            areas.append(cv2.floodFill(region, None, (c, r), mark, 0, 0, 8)[0])
        sizes[i] = areas[mark]
    return sizes


def labelled_sizes(region: np.ndarray, seeds: IntArray) -> IntArray:
    """The sizes of the regions (nonzero cells, 8-connected) of ``region`` that hold each
    of ``seeds`` (rows of (row, col)), labelled all at once."""
    _, labels, stats, _ = cv2.connectedComponentsWithStats(
        (region > 0).view(np.uint8), connectivity=8
    )
    sizes: IntArray = stats[labels[seeds[:, 0], seeds[:, 1]], cv2.CC_STAT_AREA].astype(np.intp)
    return sizes
