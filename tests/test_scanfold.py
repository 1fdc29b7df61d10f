"""Phase 5: a noiseless scan cast and folded in one compiled call maps what the two-call
path maps, byte for byte (walls, other robots' bodies, the safe space, the update window);
so do the scans of a robot's turn held back and folded together."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mresim_phys.knowledge.mapping import integrate_scan
from mresim_phys.knowledge.scanfold import ScanQueue, folds_in_one_call, scan_into_map
from mresim_phys.planning.grid import union_box
from mresim_phys.types import UNKNOWN
from mresim_phys.world.sensing import Laser, scan
from mresim_phys.world.space import World


def rubble(seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    occupied = rng.random((60, 80)) < 0.04
    occupied[0] = occupied[-1] = occupied[:, 0] = occupied[:, -1] = True
    occupied[20:24, 10:50] = True
    return occupied


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    fov=st.sampled_from([180.0, 270.0, 360.0]),
    robots_block=st.booleans(),
)
def test_one_call_maps_what_scan_then_fold_maps(seed: int, fov: float, robots_block: bool) -> None:
    occupied = rubble(seed)
    world = World(occupied, [0.5, 0.5, 0.5])
    rng = np.random.default_rng(seed)
    free_cells = np.argwhere(~occupied)
    spots = free_cells[rng.choice(len(free_cells), 3, replace=False)]
    world.place_robots([(float(c) + 0.5, float(r) + 0.5) for r, c in spots])
    origin = (float(spots[0][1]) + 0.5, float(spots[0][0]) + 0.5)
    heading = float(rng.uniform(-np.pi, np.pi))
    laser = Laser(range=float(rng.uniform(5.0, 60.0)), fov_deg=fov, rays=181)
    shape_filter = world.query_filter(0, robots_block)
    beliefs = [np.full(occupied.shape, UNKNOWN, dtype=np.uint8) for _ in range(2)]
    safes = [np.zeros(occupied.shape, dtype=bool) for _ in range(2)]
    for _ in range(2):  # a second scan from a turned heading folds into a map that knows some
        one = scan_into_map(world, origin, heading, laser, shape_filter, beliefs[0], safes[0])
        result = scan(world, origin, heading, laser, shape_filter)
        two = integrate_scan(beliefs[1], safes[1], result, laser.safe_fraction)
        assert (one is None) == (two is None)
        if one is not None and two is not None:
            assert (one.row0, one.col0) == (two.row0, two.col0)
            np.testing.assert_array_equal(one.free, two.free)
        np.testing.assert_array_equal(beliefs[0], beliefs[1])
        np.testing.assert_array_equal(safes[0], safes[1])
        heading += 1.0


@pytest.mark.parametrize(
    ("noise", "observed", "one_call"), [(0.0, False, True), (0.2, False, False), (0.0, True, False)]
)
def test_noise_and_latest_observations_take_the_two_call_path(
    noise: float, observed: bool, one_call: bool
) -> None:
    stamps = np.zeros((4, 4), dtype=np.int32) if observed else None
    assert folds_in_one_call(Laser(range=10.0, noise_std=noise), stamps) is one_call


class Holder:
    """A robot's map and safe cells, as a ScanQueue folds into them."""

    def __init__(self, shape: tuple[int, int]) -> None:
        self.belief = np.full(shape, UNKNOWN, dtype=np.uint8)
        self.safe = np.zeros(shape, dtype=bool)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), robots_block=st.booleans(), scans=st.integers(1, 9))
def test_held_scans_fold_as_scans_one_at_a_time(seed: int, robots_block: bool, scans: int) -> None:
    """A robot's turn holds its scans (ScanQueue) and folds them in one call: the same map,
    safe cells and (union) window as folding each scan when it is taken."""
    occupied = rubble(seed)
    world = World(occupied, [0.5, 0.5, 0.5])
    rng = np.random.default_rng(seed)
    free_cells = np.argwhere(~occupied)
    spots = free_cells[rng.choice(len(free_cells), 3 + scans, replace=False)]
    world.place_robots([(float(c) + 0.5, float(r) + 0.5) for r, c in spots[:3]])
    laser = Laser(range=float(rng.uniform(5.0, 60.0)), rays=181)
    shape_filter = world.query_filter(0, robots_block)
    held, at_once = Holder(occupied.shape), Holder(occupied.shape)
    queue = ScanQueue(world, laser, shape_filter, held)
    window = None
    for r, c in spots[3:]:
        origin = (float(c) + rng.uniform(0.0, 1.0), float(r) + rng.uniform(0.0, 1.0))
        heading = float(rng.uniform(-np.pi, np.pi))
        queue.add(origin, heading)
        update = scan_into_map(
            world, origin, heading, laser, shape_filter, at_once.belief, at_once.safe
        )
        if update is not None:
            h, w = update.free.shape
            window = union_box(window, (update.row0, update.row0 + h, update.col0, update.col0 + w))
    assert (held.belief == UNKNOWN).all()  # nothing folds before it is asked to
    assert queue.fold() == window
    np.testing.assert_array_equal(held.belief, at_once.belief)
    np.testing.assert_array_equal(held.safe, at_once.safe)
    assert queue.poses == [] and queue.fold() is None  # folded once
