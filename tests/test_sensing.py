"""Sensing: rays stop exactly where the true grid has a wall."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mresim_phys.scenario.schema import SensorSpec
from mresim_phys.world.sensing import ray_offsets, scan
from mresim_phys.world.space import World


def walls_only(world: World) -> tuple[int, int, int]:
    return world.query_filter(None, robots_block=False)


def test_scan_has_181_rays_over_180_degrees_centred_on_heading() -> None:
    offsets = ray_offsets(180.0, 181)
    assert len(offsets) == 181
    assert np.allclose(np.diff(np.degrees(offsets)), 1.0)
    assert offsets[90] == pytest.approx(0.0)


def test_ray_hits_wall_face_where_the_grid_says(rooms: np.ndarray) -> None:
    world = World(rooms, [])
    result = scan(world, (10.5, 30.5), 0.0, SensorSpec(range=100), walls_only(world))
    ahead = result.ranges[90]  # straight along +x: the wall at column 40 (door is rows 25-36)
    assert ahead == pytest.approx(78 - 10.5)  # through the door to the right outer wall
    result = scan(world, (10.5, 10.5), 0.0, SensorSpec(range=100), walls_only(world))
    assert result.ranges[90] == pytest.approx(40 - 10.5)
    assert result.wall_hit[90]
    up = scan(world, (10.5, 10.5), -math.pi / 2, SensorSpec(range=100), walls_only(world))
    assert up.ranges[90] == pytest.approx(10.5 - 2)


def test_rays_never_exceed_range_and_stop_at_max_in_open_space() -> None:
    world = World(np.zeros((200, 200), dtype=bool), [])
    result = scan(world, (100.0, 100.0), 0.3, SensorSpec(range=50), walls_only(world))
    assert np.all(result.ranges == 50)
    assert not result.wall_hit.any()


def test_rays_match_exact_grid_traversal(rooms: np.ndarray, rng: np.random.Generator) -> None:
    world = World(rooms, [])
    free = np.argwhere(~rooms)
    for row, col in free[rng.choice(len(free), 30, replace=False)]:
        origin = (col + rng.random(), row + rng.random())
        result = scan(
            world, origin, rng.uniform(-np.pi, np.pi), SensorSpec(range=200), walls_only(world)
        )
        dirs = np.column_stack((np.cos(result.angles), np.sin(result.angles)))
        inside = np.asarray(origin) + (result.ranges[:, None] + 1e-6) * dirs
        before = np.asarray(origin) + (result.ranges[:, None] - 1e-6) * dirs
        assert rooms[inside[:, 1].astype(int), inside[:, 0].astype(int)].mean() > 0.99
        assert not rooms[before[:, 1].astype(int), before[:, 0].astype(int)].any()


def test_noise_is_reproducible_and_bounded(rooms: np.ndarray) -> None:
    world = World(rooms, [])
    sensor = SensorSpec(range=30, noise_std=0.5)
    a = scan(world, (10.5, 10.5), 0.0, sensor, walls_only(world), np.random.default_rng(1))
    b = scan(world, (10.5, 10.5), 0.0, sensor, walls_only(world), np.random.default_rng(1))
    assert np.array_equal(a.ranges, b.ranges)
    assert np.all((a.ranges >= 0) & (a.ranges <= 30))


def test_robots_block_rays_only_when_enabled(rooms: np.ndarray) -> None:
    world = World(rooms, [1.0, 1.0])
    world.place_robots([(10.5, 10.5), (20.5, 10.5)])
    open_filter = world.query_filter(0, robots_block=False)
    blocking = world.query_filter(0, robots_block=True)
    assert scan(world, (10.5, 10.5), 0.0, SensorSpec(), open_filter).ranges[90] == pytest.approx(
        29.5
    )
    blocked = scan(world, (10.5, 10.5), 0.0, SensorSpec(), blocking)
    assert blocked.ranges[90] == pytest.approx(9.0)
    assert not blocked.wall_hit[90]


def test_ray_ending_just_past_a_wall_still_hits_it(rooms: np.ndarray) -> None:
    """Regression: Chipmunk's spatial hash missed this hit; the world must not."""
    world = World(rooms, [])
    angle = math.atan2(44.904234218689126 - 30.0, 1.880607346992548 - 60.0)
    result = world.cast_rays((60.0, 30.0), np.array([angle]), 60.0, walls_only(world))
    assert result.wall_hit[0]
    assert result.ranges[0] == pytest.approx(math.hypot(58.0, 44.87361696714561 - 30.0))


def test_scans_agree_with_chipmunk_queries_of_the_space(
    rooms: np.ndarray, rng: np.random.Generator
) -> None:
    """The compiled scan and a Chipmunk segment query of the Space find the same first hit
    (walls and blocking robots alike): distance, surface normal and what was hit."""
    world = World(rooms, [1.0, 1.5, 0.8])
    centres = [(10.5, 10.5), (24.2, 12.7), (15.3, 30.1)]
    world.place_robots(centres)
    free = np.argwhere(~rooms)
    for robots_block in (False, True):
        shape_filter = world.query_filter(0, robots_block)
        for row, col in free[rng.integers(0, len(free), 60)]:
            origin = (col + rng.uniform(0.01, 0.99), row + rng.uniform(0.01, 0.99))
            if min(math.dist(origin, c) for c in centres[1:]) < 2.0:
                continue  # a robot never stands inside another one
            angles = rng.uniform(-np.pi, np.pi, 30)  # not through cell corners
            result = world.cast_rays(origin, angles, 80.0, shape_filter)
            for k, angle in enumerate(angles):
                end = (origin[0] + 80 * math.cos(angle), origin[1] + 80 * math.sin(angle))
                hit = world.first_hit(origin, end, 0.0, shape_filter)
                if hit is None:
                    assert result.ranges[k] == 80.0 and not result.wall_hit[k]
                    continue
                assert result.ranges[k] == pytest.approx(hit.alpha * 80, abs=1e-9)
                assert result.normals[k] == pytest.approx(hit.normal, abs=1e-9)
                assert result.wall_hit[k] == hit.is_wall


def test_a_ray_through_a_wall_corner_stops_there(rooms: np.ndarray) -> None:
    """A 45 degree ray through the corner where two wall cells touch diagonally does not
    slip between them, and a ray grazing a wall's corner touches it."""
    grid = np.zeros((10, 10), dtype=bool)
    grid[4, 5] = grid[5, 4] = True  # touching at the corner (5, 5)
    world = World(grid, [])
    through = world.cast_rays((3.5, 3.5), np.array([math.pi / 4]), 20.0, walls_only(world))
    assert through.wall_hit[0] and through.ranges[0] == pytest.approx(1.5 * math.sqrt(2))
    grid = np.zeros((10, 10), dtype=bool)
    grid[4, 5] = True  # its lower-left corner is (5, 5)
    world = World(grid, [])
    grazing = world.cast_rays((3.5, 6.5), np.array([-math.pi / 4]), 20.0, walls_only(world))
    assert grazing.wall_hit[0] and grazing.ranges[0] == pytest.approx(1.5 * math.sqrt(2))


def test_a_ray_along_a_cell_boundary_touches_walls_on_both_sides() -> None:
    """A robot on a whole coordinate looking along an axis: its ray runs on the line
    between two columns and stops at a wall on either side of it."""
    grid = np.zeros((10, 10), dtype=bool)
    grid[2, 4] = True  # left of the line x = 5
    world = World(grid, [])
    up = world.cast_rays((5.0, 8.0), np.array([-math.pi / 2]), 20.0, walls_only(world))
    assert up.wall_hit[0] and up.ranges[0] == pytest.approx(5.0)
    grid[2, 4], grid[6, 7] = False, True  # below the line y = 6
    world = World(grid, [])
    right = world.cast_rays((1.0, 6.0), np.array([0.0]), 20.0, walls_only(world))
    assert right.wall_hit[0] and right.ranges[0] == pytest.approx(6.0)
