"""'latest' beliefs in a world that changes: scans overwrite, exchange keeps the newer
observation, paths blocked by what a robot now senses are dropped, metrics follow."""

from __future__ import annotations

import numpy as np
import pytest

from mresim_phys.comms.deltas import merge_cells, tile_shape
from mresim_phys.knowledge.latest import LatestCoverage
from mresim_phys.knowledge.mapping import integrate_scan
from mresim_phys.motion import path_blocked
from mresim_phys.sim import Simulation
from mresim_phys.types import FREE, OCCUPIED, UNKNOWN
from mresim_phys.world.sensing import Laser, scan
from mresim_phys.world.space import World


def fresh(shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return (
        np.full(shape, UNKNOWN, np.uint8),
        np.zeros(shape, bool),
        np.full(shape, -1, np.int32),
    )


def test_a_cell_seen_occupied_then_seen_free_is_free() -> None:
    truth = np.zeros((40, 60), dtype=bool)
    truth[0, :] = truth[-1, :] = truth[:, 0] = truth[:, -1] = True
    world = World(truth, [])
    world.add_movable("person", (3, 3), (18, 30))
    laser = Laser(range=50, fov_deg=180, rays=181)
    belief, safe, observed = fresh(truth.shape)
    look = scan(world, (10.5, 19.5), 0.0, laser, world.query_filter(None, False))
    integrate_scan(belief, safe, look, laser.safe_fraction, observed, step=1)
    assert belief[19, 30] == OCCUPIED and observed[19, 30] == 1
    world.remove_movable("person")
    look = scan(world, (10.5, 19.5), 0.0, laser, world.query_filter(None, False))
    integrate_scan(belief, safe, look, laser.safe_fraction, observed, step=2)
    assert belief[19, 30] == FREE and observed[19, 30] == 2


def test_without_observation_steps_only_a_ray_through_clears_an_obstacle() -> None:
    truth = np.zeros((40, 60), dtype=bool)
    truth[0, :] = truth[-1, :] = truth[:, 0] = truth[:, -1] = True
    world = World(truth, [])
    laser = Laser(range=50, fov_deg=180, rays=181)
    belief, safe, _ = fresh(truth.shape)
    belief[19, 30] = OCCUPIED  # in front of the robot: a ray goes right through it
    belief[19, 5] = OCCUPIED  # behind it: no ray sees it
    look = scan(world, (10.5, 19.5), 0.0, laser, world.query_filter(None, False))
    integrate_scan(belief, safe, look, laser.safe_fraction)
    assert belief[19, 30] == FREE  # 'grow' beliefs: walls are solid, that one was false
    assert belief[19, 5] == OCCUPIED


@pytest.mark.parametrize(
    ("mine", "theirs", "expected"),
    [
        ((OCCUPIED, 5), (FREE, 9), (FREE, 9)),  # newer free wins over older obstacle
        ((FREE, 9), (OCCUPIED, 5), (FREE, 9)),  # older obstacle loses
        ((FREE, 7), (OCCUPIED, 7), (OCCUPIED, 7)),  # same step: the obstacle
        ((UNKNOWN, -1), (FREE, 3), (FREE, 3)),
    ],
)
def test_exchange_keeps_the_newer_observation(
    mine: tuple[int, int], theirs: tuple[int, int], expected: tuple[int, int]
) -> None:
    belief, safe, observed = fresh((1, 4))
    belief[0, 2], observed[0, 2] = mine
    codes = belief.copy()
    stamps = np.full((1, 4), -1, np.int32)
    tiles = np.full(tile_shape((1, 4)), -1, np.int32)
    origins = np.full((1, 4), -1, np.int16)
    index = np.array([2], np.int64)
    merge_cells(index, np.array([theirs[0]], np.uint8), np.array([theirs[1]], np.int32),
                belief, safe, observed, codes, stamps, tiles, origins, 11, 1)  # fmt: skip
    assert (int(belief[0, 2]), int(observed[0, 2])) == expected


def test_a_path_is_blocked_only_where_the_body_cannot_pass() -> None:
    belief = np.full((20, 20), FREE, np.uint8)
    path = np.array([[2.5, 10.5], [3.5, 10.5], [4.5, 10.5], [5.5, 10.5], [6.5, 10.5]])
    belief[12, 5] = OCCUPIED  # 2 rows away: a body of radius 1.4 passes it
    assert not path_blocked(belief, path, 1.4, 10.0)
    belief[11, 5] = OCCUPIED  # next to the path: within the body
    assert path_blocked(belief, path, 1.4, 10.0)
    assert not path_blocked(belief, path, 0.5, 10.0)  # a thin body passes it
    assert not path_blocked(belief, path, 1.4, 1.5)  # beyond the lookahead


def test_stale_counts_maps_that_disagree_with_the_truth() -> None:
    truth = np.zeros((10, 10), dtype=bool)
    reachable = ~truth
    coverage = LatestCoverage(reachable, truth)
    belief = np.full((10, 10), UNKNOWN, np.uint8)
    belief[2:5, 2:5] = FREE
    coverage.touch_box(belief, (0, 10, 0, 10))
    coverage.settle()
    assert coverage.count == 9 and coverage.stale == 0
    truth[3, 3] = True  # something moved onto a cell the robot holds FREE
    reachable = ~truth
    coverage.retarget(reachable, (3, 4, 3, 4))
    assert coverage.stale == 1 and coverage.count == 8 and coverage.total == 99
    belief[3, 3] = OCCUPIED  # the robot sees it
    coverage.touch_box(belief, (3, 4, 3, 4))
    coverage.settle()
    assert coverage.stale == 0
    truth[3, 3] = False  # ... and it leaves: the map is stale until seen again
    coverage.retarget(~truth, (3, 4, 3, 4))
    assert coverage.stale == 1 and coverage.count == 8


def test_doors_and_people_scenario_runs_the_same_twice() -> None:
    runs = []
    for _ in range(2):
        sim = Simulation.from_yaml("scenarios/14_office_people_doors.yaml", steps=120)
        rows = [(r.explored, r.known_at_base, r.stale) for r in sim.iterate()]
        runs.append(rows)
    assert runs[0] == runs[1]
    assert runs[0][-1][2] is not None  # the stale column exists in a changing world
