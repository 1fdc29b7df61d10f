"""Reachable free space and coverage follow a changing world (world/reach.py, Coverage.retarget)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.typing import NDArray
from scipy import ndimage

from mresim_phys.knowledge.coverage import Coverage
from mresim_phys.types import FREE, UNKNOWN
from mresim_phys.world.changes import Change
from mresim_phys.world.reach import Reachable, follow_changes
from mresim_phys.world.space import World

Grid = NDArray[np.bool_]


def labelled(occupied: Grid, seeds: NDArray[np.intp]) -> Grid:
    """Reference: free cells 4-connected to a free seed, by one full labelling."""
    labels, _ = ndimage.label(~occupied)
    ids = {int(labels[r, c]) for r, c in seeds if not occupied[r, c]}
    return np.isin(labels, sorted(ids))


def two_rooms() -> Grid:
    """40 x 60: a wall at column 30 with a door at rows 18-21; left and right rooms."""
    grid = np.zeros((40, 60), dtype=bool)
    grid[:, 30] = True
    grid[18:22, 30] = False
    return grid


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_followed_reachable_set_equals_a_full_labelling(seed: int) -> None:
    rng = np.random.default_rng(seed)
    rows, cols = rng.integers(12, 40, 2)
    grid = rng.random((rows, cols)) < rng.uniform(0.05, 0.45)
    starts = rng.integers(0, (rows, cols), (int(rng.integers(1, 4)), 2))
    grid[starts[:, 0], starts[:, 1]] = False
    world = World(grid, [])
    reachable = Reachable(world.occupied, starts[:, ::-1] + 0.5)
    pending: list[Change] = []
    follows = 0
    for _ in range(30):
        r0, c0 = rng.integers(0, rows - 1), rng.integers(0, cols - 1)
        r1, c1 = min(rows, r0 + rng.integers(1, 4)), min(cols, c0 + rng.integers(1, 4))
        cells = rng.random((r1 - r0, c1 - c0)) < 0.5
        pending.append(world.set_cells((r0, r1, c0, c1), cells))
        if rng.random() < 0.5:
            reachable.follow(world.occupied, pending)
            pending, follows = [], follows + 1
            np.testing.assert_array_equal(reachable.mask, labelled(world.occupied, starts))
    assert reachable.relabels <= follows


def test_a_cart_moving_in_a_room_is_followed_without_relabelling_the_map() -> None:
    world = World(two_rooms(), [])
    reachable = Reachable(world.occupied, [(5.5, 5.5)])
    world.add_movable("cart", (3, 3), (10, 10))
    for col in range(11, 20):
        change = world.move_movable("cart", (10, col))
        window, _ = reachable.follow(world.occupied, [change])
        assert window[1] - window[0] < 10 and window[3] - window[2] < 10
        np.testing.assert_array_equal(reachable.mask, labelled(world.occupied, np.array([[5, 5]])))
    assert reachable.relabels == 0
    assert not reachable.mask[10:13, 19:22].any()


def test_a_door_closing_is_detected_and_relabels_the_map() -> None:
    world = World(two_rooms(), [])
    reachable = Reachable(world.occupied, [(5.5, 5.5)])
    assert reachable.mask[:, 31:].all()
    reachable.follow(world.occupied, [world.set_cells((18, 22, 30, 31), True)])
    assert reachable.relabels == 1
    assert not reachable.mask[:, 30:].any() and reachable.mask[:, :30].all()


def test_a_seed_inside_the_changed_window_keeps_its_closed_room() -> None:
    grid = np.zeros((30, 30), dtype=bool)
    grid[10:17, 10:17] = True
    grid[11:16, 11:16] = False  # a closed 5 x 5 room around the seed
    world = World(grid, [])
    reachable = Reachable(world.occupied, [(13.5, 13.5), (1.5, 1.5)])
    reachable.follow(world.occupied, [world.set_cells((12, 13, 12, 13), True)])
    assert reachable.relabels == 0  # the room's connectivity to the outside did not change
    np.testing.assert_array_equal(
        reachable.mask, labelled(world.occupied, np.array([[13, 13], [1, 1]]))
    )
    assert reachable.mask[11:16, 11:16].sum() == 24


def test_a_buried_seed_stops_seeding_until_uncovered() -> None:
    world = World(two_rooms(), [])
    reachable = Reachable(world.occupied, [(45.5, 5.5)])  # in the right room
    reachable.follow(world.occupied, [world.set_cells((18, 22, 30, 31), True)])  # door closed
    assert not reachable.mask[:, :30].any()
    reachable.follow(world.occupied, [world.set_cells((0, 40, 31, 60), True)])  # right room fills
    assert not reachable.mask.any()
    change = world.set_cells((0, 40, 31, 60), False)
    reachable.follow(world.occupied, [change])
    assert reachable.mask[:, 31:].all() and not reachable.mask[:, :31].any()


def test_reachable_rejects_a_blocked_start_like_free_components_mask() -> None:
    grid = two_rooms()
    with pytest.raises(Exception, match="obstacle"):
        Reachable(grid, [(30.5, 5.5)])


def coverage_with(world: World, reachable: Reachable, known: Grid) -> Coverage:
    """A coverage counter that has seen ``known`` FREE."""
    coverage = Coverage(reachable.mask)
    belief = np.where(known, FREE, UNKNOWN).astype(np.uint8)
    coverage.add_cells(belief == FREE, 0, 0)
    return coverage


def test_closing_a_door_takes_the_far_room_out_of_the_denominator() -> None:
    world = World(two_rooms(), [])
    reachable = Reachable(world.occupied, [(5.5, 5.5)])
    known = np.zeros(world.shape, dtype=bool)
    known[:, :10] = True  # the team has seen part of the left room
    coverage = coverage_with(world, reachable, known)
    left, right = 40 * 30, 40 * 29 + 4  # free cells: left room; right room and the door
    assert coverage.total == left + right
    follow_changes(coverage, reachable, world.occupied, [world.set_cells((18, 22, 30, 31), True)])
    assert coverage.total == left and coverage.count == 400
    assert coverage.fraction == pytest.approx(400 / left)


def test_opening_a_door_adds_the_new_area() -> None:
    grid = two_rooms()
    grid[18:22, 30] = True
    world = World(grid, [])
    reachable = Reachable(world.occupied, [(5.5, 5.5)])
    coverage = coverage_with(world, reachable, reachable.mask)  # the left room, all seen
    assert coverage.total == 1200 and coverage.fraction == 1.0
    follow_changes(coverage, reachable, world.occupied, [world.set_cells((18, 22, 30, 31), False)])
    assert coverage.total == 1200 + 4 + 40 * 29
    assert coverage.count == 1200 and coverage.fraction == pytest.approx(1200 / coverage.total)


def test_following_nothing_changes_nothing() -> None:
    world = World(two_rooms(), [])
    reachable = Reachable(world.occupied, [(5.5, 5.5)])
    coverage = coverage_with(world, reachable, ~world.occupied)
    mask, count, total = reachable.mask, coverage.count, coverage.total
    follow_changes(coverage, reachable, world.occupied, [world.set_cells((0, 2, 0, 2), False)])
    assert reachable.mask is mask and (coverage.count, coverage.total) == (count, total)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_coverage_follows_changes_as_a_full_recount_and_stays_in_bounds(seed: int) -> None:
    rng = np.random.default_rng(seed)
    grid = rng.random((30, 40)) < 0.25
    grid[0, 0] = False
    world = World(grid, [])
    reachable = Reachable(world.occupied, [(0.5, 0.5)])
    coverage = coverage_with(world, reachable, rng.random(grid.shape) < 0.5)
    for _ in range(20):
        r0, c0 = rng.integers(0, 29), rng.integers(0, 39)
        change = world.set_cells((r0, r0 + 2, c0, c0 + 2), bool(rng.random() < 0.6))
        follow_changes(coverage, reachable, world.occupied, [change])
        seen = np.zeros(grid.shape, dtype=bool)
        seen[rng.integers(0, 30, 5), rng.integers(0, 40, 5)] = True
        coverage.add_cells(seen & ~world.occupied, 0, 0)
        assert coverage.total == np.count_nonzero(reachable.mask)
        assert coverage.count == np.count_nonzero(coverage.known & reachable.mask)
        assert 0.0 <= coverage.fraction <= 1.0
