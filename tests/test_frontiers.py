"""Phase 3b: frontier cells, clusters and the cheapest place to look at each cluster from."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import ndimage

from mresim_phys.knowledge.frontiers import (
    find_frontiers,
    frontier_mask,
    label_cells,
)
from mresim_phys.knowledge.targets import frontier_targets
from mresim_phys.planning.fields import distance_field, traversable
from mresim_phys.types import FREE, OCCUPIED, UNKNOWN

SEEDS = st.integers(0, 2**32 - 1)
EIGHT = np.ones((3, 3), dtype=bool)


def random_belief(seed: int, shape: tuple[int, int] | None = None) -> np.ndarray:
    """Blobby random belief: smoothed noise thresholded into unknown / free / occupied."""
    rng = np.random.default_rng(seed)
    if shape is None:
        shape = (int(rng.integers(4, 40)), int(rng.integers(4, 40)))
    noise = ndimage.gaussian_filter(rng.random(shape), rng.uniform(0.0, 2.0))
    lo, hi = np.quantile(noise, sorted(rng.uniform(0, 1, size=2)))
    belief = np.full(shape, FREE, dtype=np.uint8)
    belief[noise < lo] = UNKNOWN
    belief[noise > hi] = OCCUPIED
    return belief


def brute_frontier(belief: np.ndarray) -> np.ndarray:
    """FREE cells with an UNKNOWN 8-neighbour, cells outside the grid not unknown, except a
    diagonal neighbour behind two OCCUPIED cells (the wall corner hides it)."""
    padded = np.pad(belief == UNKNOWN, 1, constant_values=False)
    walls = np.pad(belief == OCCUPIED, 1, constant_values=False)
    rows, cols = belief.shape
    near = np.zeros(belief.shape, dtype=bool)
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            seen = padded[1 + dr : 1 + dr + rows, 1 + dc : 1 + dc + cols].copy()
            if dr and dc:
                beside = walls[1 + dr : 1 + dr + rows, 1 : 1 + cols]
                seen &= ~(beside & walls[1 : 1 + rows, 1 + dc : 1 + dc + cols])
            near |= seen
    return near & (belief == FREE)


def test_a_diagonal_wall_hides_the_unknown_behind_its_corners() -> None:
    """Cells along a staircase wall are not frontier; a gap in the wall is."""
    belief = np.full((8, 8), FREE, dtype=np.uint8)
    for i in range(8):
        belief[i, i] = OCCUPIED
        belief[i, i + 1 :] = UNKNOWN
    assert not frontier_mask(belief).any()
    belief[3, 3] = UNKNOWN  # a cell of the wall never seen: the unknown shows through
    assert frontier_mask(belief)[3, 2] and frontier_mask(belief)[4, 3]


def as_set(cells: np.ndarray) -> set[tuple[int, int]]:
    return {(int(r), int(c)) for r, c in cells}


# --------------------------------------------------------------------------- find_frontiers


@settings(max_examples=150, deadline=None)
@given(seed=SEEDS)
def test_clusters_are_exactly_the_8_connected_frontier_components(seed: int) -> None:
    belief = random_belief(seed)
    expected = brute_frontier(belief)
    np.testing.assert_array_equal(frontier_mask(belief), expected)
    fr = find_frontiers(belief, min_size=1)
    cells = fr.cells_rc
    # every frontier cell is FREE and touches UNKNOWN, and every such cell is in a cluster
    assert as_set(cells) == as_set(np.argwhere(expected))
    assert (belief[cells[:, 0], cells[:, 1]] == FREE).all()
    # same partition as scipy's 8-connected labelling
    labels, n = ndimage.label(expected, structure=EIGHT)
    assert len(fr) == n
    theirs = labels[cells[:, 0], cells[:, 1]]
    pairs = set(zip(fr.cluster_of.tolist(), theirs.tolist(), strict=True))
    assert len(pairs) == n
    # bookkeeping: sizes, centroids, raster order of cells and of clusters
    assert fr.sizes.sum() == len(cells)
    np.testing.assert_array_equal(fr.sizes, np.bincount(fr.cluster_of, minlength=len(fr)))
    flat = cells[:, 0] * belief.shape[1] + cells[:, 1]
    assert (np.diff(flat) > 0).all()
    first = [flat[fr.cluster_of == j][0] for j in range(len(fr))]
    assert first == sorted(first)
    for j in range(len(fr)):
        mine = cells[fr.cluster_of == j]
        np.testing.assert_allclose(fr.centroids[j], mine[:, ::-1].mean(axis=0) + 0.5)


@settings(max_examples=60, deadline=None)
@given(seed=SEEDS, min_size=st.integers(1, 12))
def test_min_size_drops_exactly_the_small_clusters(seed: int, min_size: int) -> None:
    belief = random_belief(seed)
    every = find_frontiers(belief, min_size=1)
    kept = find_frontiers(belief, min_size=min_size)
    np.testing.assert_array_equal(kept.sizes, every.sizes[every.sizes >= min_size])
    big = np.isin(every.cluster_of, np.flatnonzero(every.sizes >= min_size))
    np.testing.assert_array_equal(kept.cells_rc, every.cells_rc[big])
    assert (kept.sizes >= min_size).all()


def test_two_separate_runs_form_two_clusters_in_raster_order() -> None:
    belief = np.full((12, 20), FREE, dtype=np.uint8)
    belief[0:3, 14:20] = UNKNOWN  # top-right pocket
    belief[9:12, 0:4] = UNKNOWN  # bottom-left pocket
    fr = find_frontiers(belief)
    assert len(fr) == 2
    assert as_set(fr.cells_rc[fr.cluster_of == 0]) == as_set(
        np.argwhere(brute_frontier(belief) & (np.arange(20) >= 10))
    )
    assert fr.sizes.tolist() == [6 + 3 + 1, 4 + 3 + 1]
    assert fr.centroids[0][0] > 10 > fr.centroids[1][0]


def test_labels_follow_the_raster_order_of_each_clusters_first_cell() -> None:
    # a U: its right arm starts on row 0 left of nothing, joins the left arm on the last row
    grid = np.zeros((4, 7), dtype=bool)
    grid[0:4, 1] = grid[0:4, 4] = grid[3, 1:5] = True  # one cluster, two arms
    grid[0, 6] = grid[1, 6] = True  # a second one, first seen after the U's first cell
    flat = np.flatnonzero(grid)
    labels = label_cells(flat, 7)
    assert labels.tolist() == [0 if (f % 7) < 6 else 1 for f in flat]
    assert label_cells(np.array([0, 8, 16], dtype=np.intp), 7).tolist() == [0, 0, 0]  # diagonal
    assert label_cells(np.array([6, 7], dtype=np.intp), 7).tolist() == [0, 1]  # no wrap


def test_fully_known_or_fully_unknown_map_has_no_frontiers() -> None:
    known = np.full((10, 10), FREE, dtype=np.uint8)
    known[4:6, 4:6] = OCCUPIED
    for belief in (known, np.zeros((10, 10), dtype=np.uint8)):
        fr = find_frontiers(belief, min_size=1)
        assert len(fr) == 0
        assert fr.cells_rc.shape == (0, 2) and fr.centroids.shape == (0, 2)


def test_walls_between_free_and_unknown_are_not_frontiers() -> None:
    belief = np.full((8, 8), FREE, dtype=np.uint8)
    belief[:, 5] = OCCUPIED
    belief[:, 6:] = UNKNOWN
    assert len(find_frontiers(belief, min_size=1)) == 0
    belief[3, 5] = FREE  # a door seen open
    fr = find_frontiers(belief, min_size=1)
    assert as_set(fr.cells_rc) == {(3, 5)}


# --------------------------------------------------------------------------- frontier_targets


def brute_targets(
    fr, costs: np.ndarray, passable: np.ndarray, reach: float
) -> tuple[np.ndarray, np.ndarray]:
    """For each cluster: min (cost, row, col) over passable cells within reach of a cell."""
    rows, cols = np.nonzero(passable & np.isfinite(costs))
    targets = np.full((len(fr), 2), -1)
    best = np.full(len(fr), np.inf)
    for j in range(len(fr)):
        mine = fr.cells_rc[fr.cluster_of == j]
        d2 = (rows[:, None] - mine[:, 0]) ** 2 + (cols[:, None] - mine[:, 1]) ** 2
        near = (d2 <= reach**2).any(axis=1)
        if near.any():
            i = np.lexsort((cols[near], rows[near], costs[rows[near], cols[near]]))[0]
            targets[j] = rows[near][i], cols[near][i]
            best[j] = costs[rows[near][i], cols[near][i]]
    return targets, best


@settings(max_examples=80, deadline=None)
@given(seed=SEEDS, reach=st.sampled_from([0.0, 0.9, 1.0, 1.5, 2.0, 3.3, 5.0, 8.0]))
def test_targets_match_brute_force(seed: int, reach: float) -> None:
    belief = random_belief(seed, (30, 36))
    passable = traversable(belief, 0.8)
    rr, cc = np.nonzero(passable)
    if len(rr) == 0:
        return
    i = np.random.default_rng(seed).integers(len(rr))
    field = distance_field(passable, (cc[i] + 0.5, rr[i] + 0.5))
    fr = find_frontiers(belief, min_size=1)
    targets, costs = frontier_targets(fr, field, passable, reach)
    expected_targets, expected_costs = brute_targets(fr, field.costs, passable, reach)
    np.testing.assert_array_equal(costs, expected_costs)
    np.testing.assert_array_equal(targets, expected_targets)


def test_target_is_the_cheap_reachable_cell_and_walled_frontiers_are_skipped() -> None:
    belief = np.full((20, 30), FREE, dtype=np.uint8)
    belief[:, 0] = belief[:, -1] = belief[0] = belief[-1] = OCCUPIED
    belief[8:11, 25:29] = UNKNOWN  # open frontier on the right
    belief[2:10, 2:12] = OCCUPIED  # a closed room with thick walls (3 cells)...
    belief[5:7, 5:9] = FREE  # ...free cells inside...
    belief[5, 6] = UNKNOWN  # ...and an unknown speck: a frontier behind walls
    passable = traversable(belief, 0.5)
    field = distance_field(passable, (15.5, 15.5))
    fr = find_frontiers(belief, min_size=1)
    assert len(fr) == 2
    targets, costs = frontier_targets(fr, field, passable, reach=2.0)
    walled, open_ = (0, 1) if fr.centroids[0][0] < 10 else (1, 0)
    assert costs[walled] == np.inf and targets[walled].tolist() == [-1, -1]
    assert np.isfinite(costs[open_])
    row, col = targets[open_]
    assert passable[row, col] and field.reachable(int(row), int(col))
    # it is the cheapest cell within reach: two columns left of the frontier's left edge
    assert col == 22 and 7 <= row <= 11
    assert costs[open_] == pytest.approx(field.costs[row, col])


def test_no_frontiers_or_no_field_gives_empty_or_inf() -> None:
    belief = np.full((10, 10), FREE, dtype=np.uint8)
    passable = traversable(belief, 0.5)
    field = distance_field(passable, (5.0, 5.0))
    targets, costs = frontier_targets(find_frontiers(belief), field, passable, 3.0)
    assert targets.shape == (0, 2) and costs.shape == (0,)
    belief[0, :] = UNKNOWN
    fr = find_frontiers(belief)
    nowhere = distance_field(np.zeros_like(passable), (5.0, 5.0))
    targets, costs = frontier_targets(fr, nowhere, passable, 3.0)
    assert np.isinf(costs).all() and (targets == -1).all()


@settings(max_examples=80, deadline=None)
@given(
    seed=SEEDS,
    rows=st.integers(3, 30),
    cols=st.integers(3, 40),
    excluded=st.booleans(),
)
def test_frontier_cells_are_the_brute_force_ones_in_raster_order(
    seed: int, rows: int, cols: int, excluded: bool
) -> None:
    """The compiled pass over the FREE cells' box lists exactly the brute-force frontier
    cells, in raster order, with and without excluded cells, also with FREE cells on the
    grid's edges and corners and in a grid not in C order."""
    belief = random_belief(seed, (rows, cols))
    rng = np.random.default_rng(seed)
    belief[rng.integers(0, rows), [0, -1]] = FREE  # free cells on the side edges
    belief[[0, -1], rng.integers(0, cols)] = FREE  # ... and on the top and bottom ones
    exclude = rng.random(belief.shape) < 0.2 if excluded else None
    expected = np.argwhere(brute_frontier(belief) & (True if exclude is None else ~exclude))
    found = find_frontiers(belief, min_size=1, exclude=exclude)
    np.testing.assert_array_equal(found.cells_rc, expected.reshape(-1, 2))
    other = find_frontiers(np.asfortranarray(belief), min_size=1, exclude=exclude)
    np.testing.assert_array_equal(other.cells_rc, found.cells_rc)
    np.testing.assert_array_equal(other.cluster_of, found.cluster_of)
