"""Frontier regions: the seen-but-unvisited space each frontier cluster borders."""

from __future__ import annotations

import cv2
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from mresim_phys.knowledge.frontier_regions import LAST_MARK, region_sizes
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


def labelled_reference(belief: np.ndarray, safe: np.ndarray, min_size: int = 3) -> list[int]:
    """Every region labelled at once (connected components, 8-connected): the sizes the
    fills must give."""
    frontiers = find_frontiers(belief, min_size)
    region = (belief == FREE) & ~safe
    cells = frontiers.cells_rc
    region[cells[:, 0], cells[:, 1]] = True
    _, labels, stats, _ = cv2.connectedComponentsWithStats(region.view(np.uint8), connectivity=8)
    _, first = np.unique(frontiers.cluster_of, return_index=True)
    return [int(stats[labels[r, c], cv2.CC_STAT_AREA]) for r, c in cells[first]]


@given(seed=st.integers(0, 2**32 - 1), walls=st.floats(0.0, 0.6))
@settings(max_examples=60, deadline=None)
def test_filling_the_regions_of_the_clusters_gives_what_labelling_all_gives(
    seed: int, walls: float
) -> None:
    rng = np.random.default_rng(seed)
    belief = rng.choice(
        [UNKNOWN, FREE, OCCUPIED], size=(40, 50), p=[0.2, 0.8 - walls * 0.8, walls * 0.8]
    )
    belief = belief.astype(np.uint8)
    safe = rng.random(belief.shape) < 0.3
    if bbox(belief == FREE) is None or len(find_frontiers(belief)) == 0:
        return
    assert sizes_of(belief, safe) == labelled_reference(belief, safe)


def test_past_the_last_mark_every_region_is_labelled_at_once() -> None:
    """300 one-cell rooms each with an unknown cell above: more regions with a frontier
    than a byte can mark, and each still weighs its own cells."""
    belief = np.full((4, 2 * 300 + 1), OCCUPIED, dtype=np.uint8)
    belief[1, 1::2] = UNKNOWN
    belief[2, 1::2] = FREE
    safe = np.zeros(belief.shape, dtype=bool)
    frontiers = find_frontiers(belief, 1)
    assert len(np.unique(frontiers.cluster_of)) == 300 > LAST_MARK - 1
    sizes = region_sizes(frontiers, belief, safe, (2, 3, 1, 600))
    assert sizes.tolist() == labelled_reference(belief, safe, 1) == [1] * 300
