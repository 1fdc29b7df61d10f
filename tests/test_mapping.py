"""Mapping: a robot's own grid marks what its scans saw, and nothing else."""

from __future__ import annotations

import numpy as np

from mresim_phys.agents import empty_belief
from mresim_phys.mapping import Coverage, integrate_scan, merge_into
from mresim_phys.scenario import SensorSpec
from mresim_phys.sensing import scan
from mresim_phys.types import FREE, OCCUPIED, UNKNOWN
from mresim_phys.world import World


def scanned_belief(
    truth: np.ndarray, poses: list[tuple[float, float, float]], rng_range: float = 60
):
    world = World(truth, [])
    belief, safe = empty_belief(truth.shape)
    updates = []
    for x, y, heading in poses:
        result = scan(
            world, (x, y), heading, SensorSpec(range=rng_range), world.query_filter(None, False)
        )
        updates.append(integrate_scan(belief, safe, result, 0.1))
    return belief, safe, updates


def test_hit_cells_are_true_walls_and_free_cells_are_almost_all_truly_free(
    rooms: np.ndarray,
) -> None:
    poses = [(10.5, 10.5, 0.0), (20.0, 30.0, 1.0), (30.0, 45.0, -2.0), (60.0, 30.0, 3.1)]
    belief, _, _ = scanned_belief(rooms, poses)
    assert np.all(rooms[belief == OCCUPIED])
    wrongly_free = np.count_nonzero(rooms & (belief == FREE)) / np.count_nonzero(belief == FREE)
    assert wrongly_free < 0.005
    assert np.count_nonzero(belief == FREE) > 500


def test_a_wall_seen_up_close_is_not_a_frontier(rooms: np.ndarray) -> None:
    """A straight wall in view is marked along its face: no unknown cell next to the free area."""
    belief, _, _ = scanned_belief(rooms, [(20.5, 30.5, 0.0)])
    face = belief[5:20, 40]  # the dividing wall above the door, seen from the left
    free_next = belief[5:20, 39]
    assert np.all(free_next == FREE)
    assert np.all(face == OCCUPIED)


def test_unseen_side_stays_unknown(rooms: np.ndarray) -> None:
    belief, _, _ = scanned_belief(rooms, [(10.5, 10.5, 0.0)])
    assert np.all(
        belief[2:20, 43:] == UNKNOWN
    )  # beyond the dividing wall, out of view through the door
    assert belief[10, 5] == UNKNOWN  # behind the robot (180 degree field of view)


def test_safe_space_is_free_and_near_the_robot(rooms: np.ndarray) -> None:
    belief, safe, _ = scanned_belief(rooms, [(20.5, 30.5, 0.0)])
    assert safe.any()
    assert np.all(belief[safe] == FREE)
    rows, cols = np.nonzero(safe)
    assert np.hypot(cols + 0.5 - 20.5, rows + 0.5 - 30.5).max() <= 0.1 * 60 + 1.5


def test_merge_known_beats_unknown_obstacle_beats_free() -> None:
    a = np.array([UNKNOWN, FREE, FREE, OCCUPIED], dtype=np.uint8)
    b = np.array([FREE, UNKNOWN, OCCUPIED, FREE], dtype=np.uint8)
    merge_into(a, b)
    assert a.tolist() == [FREE, FREE, OCCUPIED, OCCUPIED]


def test_coverage_counts_each_reachable_cell_once_and_never_decreases(rooms: np.ndarray) -> None:
    poses = [(10.5, 10.5, 0.0), (10.5, 10.5, 0.0), (20.0, 30.0, 1.0)]
    belief, _, updates = scanned_belief(rooms, poses)
    coverage = Coverage(~rooms)
    fractions = []
    for update in updates:
        coverage.touch(belief, update)
        coverage.settle()
        fractions.append(coverage.fraction)
    assert fractions == sorted(fractions) and fractions[0] == fractions[1]
    assert coverage.count == np.count_nonzero(coverage.known)
    assert coverage.count <= np.count_nonzero(belief != UNKNOWN)
