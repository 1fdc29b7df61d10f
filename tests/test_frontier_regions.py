"""Frontier regions: the seen-but-unvisited space each frontier cluster borders."""

from __future__ import annotations

import numpy as np

from mresim_phys.knowledge.frontier_regions import region_sizes
from mresim_phys.knowledge.frontiers import find_frontiers
from mresim_phys.planning.grid import bbox
from mresim_phys.types import FREE, OCCUPIED, UNKNOWN


def two_rooms() -> np.ndarray:
    """Two known rooms side by side with a wall between, unknown above each."""
    belief = np.full((30, 61), OCCUPIED, dtype=np.uint8)
    belief[1:5, 1:60] = UNKNOWN
    belief[5:29, 1:30] = FREE
    belief[5:29, 31:60] = FREE
    return belief


def sizes_of(belief: np.ndarray, safe: np.ndarray) -> list[int]:
    frontiers = find_frontiers(belief)
    box = bbox(belief == FREE)
    assert box is not None
    return [int(s) for s in region_sizes(frontiers, belief, safe, box)]


def test_a_frontier_in_safe_space_weighs_its_own_cells() -> None:
    belief = two_rooms()
    safe = belief == FREE  # every free cell scanned from near by
    assert sizes_of(belief, safe) == [29, 29]  # the rooms' top rows


def test_a_frontier_weighs_the_unvisited_region_it_borders() -> None:
    belief = two_rooms()
    safe = np.zeros(belief.shape, dtype=bool)
    safe[5:29, 1:30] = True  # the left room visited, the right one only seen
    assert sizes_of(belief, safe) == [29, 24 * 29]


def test_clusters_of_one_region_share_its_size() -> None:
    belief = two_rooms()
    belief[1:5, 40:45] = FREE  # splits the right room's frontier in two
    safe = np.zeros(belief.shape, dtype=bool)
    right = 24 * 29 + 4 * 5  # the right room and the free notch above it
    assert sorted(sizes_of(belief, safe)) == [24 * 29, right, right]
