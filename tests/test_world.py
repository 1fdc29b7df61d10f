"""World queries (swept circles see walls the centre line misses) and changes of the world."""

from __future__ import annotations

import numpy as np
import pymunk
import pytest

from mresim_phys.world.clearance import box_clear
from mresim_phys.world.maps import wall_segments
from mresim_phys.world.space import (
    GRAZE,
    MOVABLE_CATEGORY,
    SHUFFLE_SEED,
    WALL_CATEGORY,
    World,
)
from mresim_phys.world.walls import walls_between


def test_a_swept_circle_hits_a_wall_corner_its_centre_line_passes() -> None:
    occupied = np.zeros((60, 200), dtype=bool)
    occupied[31:, 100] = True  # a wall whose top end lies 0.5 below the line y = 30.5
    world = World(occupied, [1.0])
    walls = world.query_filter(None, robots_block=False)
    assert world.first_hit((90.5, 30.5), (110.5, 30.5), 0.0, walls) is None
    hit = world.first_hit((90.5, 30.5), (110.5, 30.5), 1.0, walls)
    assert hit is not None and hit.is_wall
    assert 0.40 < hit.alpha < 0.47  # the circle touches the corner (100, 31) near x = 99.1
    assert world.blocked((90.5, 30.5), (110.5, 30.5), 1.0, walls) is not None


def test_a_swept_circle_clear_of_walls_is_not_blocked() -> None:
    occupied = np.zeros((60, 200), dtype=bool)
    occupied[33:, 100] = True
    world = World(occupied, [1.0])
    walls = world.query_filter(None, robots_block=False)
    assert world.first_hit((90.5, 30.5), (110.5, 30.5), 1.0, walls) is None


def test_a_circle_passing_a_corner_at_exactly_its_radius_grazes_it_unblocked() -> None:
    """Along cells next to a wall corner (radius 0.5, no wall margin) the body passes the
    corner at exactly its radius: touching, not entering, so the move is made; a hair
    closer it is blocked. (Blocked, the robot bumped at the same corner on every replan
    and never moved again: scenario 11 with wall_margin 0 froze at 23 % explored.)"""
    occupied = np.zeros((60, 200), dtype=bool)
    occupied[:30, 100] = True  # a wall whose bottom end, y = 30, lies 0.5 above y = 30.5
    world = World(occupied, [0.5])
    walls = world.query_filter(None, robots_block=False)
    assert world.blocked((99.5, 30.5), (100.5, 30.5), 0.5, walls) is None
    assert world.blocked((99.5, 30.49), (100.5, 30.49), 0.5, walls) is not None
    assert world.blocked((99.5, 30.5), (100.5, 30.5), 0.51, walls) is not None


# --- a world that changes (world/changes.py, world/wallset.py) ---------------------------


def walls(world: World) -> tuple[int, int, int]:
    return world.query_filter(None, robots_block=False)


def held_segments(world: World) -> list[tuple[tuple[float, ...], int]]:
    """Segments in the Space (in world coordinates), in insertion order, with their categories."""
    held = []
    for s in world.space.shapes:
        if isinstance(s, pymunk.Segment):
            a, b = s.body.local_to_world(s.a), s.body.local_to_world(s.b)
            held.append(((a.x, a.y, b.x, b.y), s.filter.categories))
    return held


def test_an_unchanged_world_is_built_exactly_as_before(rooms: np.ndarray) -> None:
    world = World(rooms, [1.0, 1.0])
    expected = wall_segments(rooms)
    np.testing.assert_array_equal(world.segments, expected)
    order = np.random.default_rng(SHUFFLE_SEED).permutation(len(expected))
    held = held_segments(world)
    assert [s for s, _ in held] == [tuple(row) for row in expected[order].tolist()]
    assert {c for _, c in held} == {WALL_CATEGORY}
    assert world.version == 0 and world.occupied is rooms


def test_set_cells_writes_the_truth_in_place_and_reports_what_flipped(rooms: np.ndarray) -> None:
    world = World(rooms, [])
    view = rooms[20:40, 30:50]  # as a renderer or a snapshot holds it
    change = world.set_cells((25, 37, 40, 42), True)  # close the door
    assert world.occupied is rooms and view[5:17, 10:12].all()
    assert world.version == change.version == 1 and change.count == 24
    (patch,) = change.patches
    assert patch.box == (25, 37, 40, 42) and patch.flipped.all() and patch.occupied.all()
    ray = world.cast_rays((10.5, 30.5), np.array([0.0]), 100.0, walls(world))
    assert ray.ranges[0] == pytest.approx(40 - 10.5)


def test_setting_cells_to_what_they_are_changes_nothing(rooms: np.ndarray) -> None:
    world = World(rooms, [])
    before = world.segments
    change = world.set_cells((0, 2, 0, 80), True)
    assert not change and change.patches == () and world.version == 0
    np.testing.assert_array_equal(world.segments, before)


def test_a_long_wall_is_split_by_an_opening_and_merged_again_when_it_closes() -> None:
    occupied = np.zeros((20, 60), dtype=bool)
    occupied[10, 5:55] = True  # one 50-cell wall: two long faces
    world = World(occupied, [])
    original = {s for s, _ in held_segments(world)}
    world.set_cells((10, 11, 29, 31), False)  # a 2-cell gap in the middle
    held = {s for s, _ in held_segments(world)}
    assert (5.0, 10.0, 29.0, 10.0) in held and (31.0, 10.0, 55.0, 10.0) in held
    assert (5.0, 11.0, 55.0, 11.0) not in {tuple(sorted(s)) for s in held}
    ray = world.cast_rays((30.0, 2.5), np.array([np.pi / 2]), 30.0, walls(world))
    assert ray.ranges[0] == pytest.approx(20 - 2.5)  # through the gap to the map's edge
    world.set_cells((10, 11, 29, 31), True)
    assert {s for s, _ in held_segments(world)} == original
    assert world.version == 2


@pytest.mark.parametrize(
    ("box", "value", "message"),
    [
        ((0, 0, 0, 5), True, "non-empty"),
        ((55, 61, 0, 5), True, "inside"),
        ((-1, 3, 0, 5), True, "inside"),
        ((0, 2, 0, 2), np.ones((3, 2), dtype=bool), "do not fit"),
        ((0, 2, 0, 2), np.ones((2, 2), dtype=np.uint8), "must be bool"),
    ],
)
def test_bad_changes_are_rejected_and_leave_the_world_as_it_was(
    rooms: np.ndarray, box: tuple[int, int, int, int], value: object, message: str
) -> None:
    world = World(rooms, [])
    before = rooms.copy()
    with pytest.raises(ValueError, match=message):
        world.set_cells(box, value)  # type: ignore[arg-type]
    np.testing.assert_array_equal(rooms, before)
    assert world.version == 0


def test_a_movable_obstacle_blocks_rays_and_motion_only_where_its_cells_are() -> None:
    world = World(np.zeros((40, 40), dtype=bool), [1.0])
    robot = world.query_filter(0, robots_block=False)
    change = world.add_movable("cart", (3, 2), (10, 20))  # rows 10-12, cols 20-21
    assert change.count == 6 and world.occupied[10:13, 20:22].all()
    assert {c for s, c in held_segments(world) if 20 <= min(s[0], s[2]) <= 22} == {MOVABLE_CATEGORY}
    hit = world.first_hit((5.5, 11.5), (35.5, 11.5), 0.0, robot)
    assert hit is not None and hit.is_wall and hit.is_movable and hit.point[0] == pytest.approx(20)
    assert world.blocked((15.0, 11.5), (25.0, 11.5), 1.0, robot) is not None
    walls = world.segments
    world.move_movable("cart", (20, 20))
    np.testing.assert_array_equal(world.segments, walls)  # its own body moved, no wall rebuilt
    assert world.blocked((15.0, 11.5), (25.0, 11.5), 1.0, robot) is None
    assert not world.occupied[10:13].any() and world.occupied[20:23, 20:22].all()
    world.remove_movable("cart")
    assert not world.occupied.any() and world.version == 3
    assert {c for _, c in held_segments(world)} == {WALL_CATEGORY}


def test_movables_and_walls_share_cells_without_losing_either() -> None:
    occupied = np.zeros((20, 20), dtype=bool)
    occupied[5, :] = True
    world = World(occupied, [])
    world.add_movable("leaf", (3, 1), (4, 8))  # across the wall
    assert not world.set_cells((4, 5, 8, 9), False)  # the leaf still stands there
    world.set_cells((4, 5, 8, 9), True)  # rubble under the leaf: no flip, a new kind
    change = world.remove_movable("leaf")
    assert sorted(map(tuple, change.patches[0].cells().tolist())) == [(6, 8)]
    assert world.occupied[4, 8] and world.occupied[5, :].all() and not world.occupied[6, 8]
    assert {c for _, c in held_segments(world)} == {WALL_CATEGORY}


def test_movables_are_named_and_must_fit_the_map() -> None:
    world = World(np.zeros((10, 10), dtype=bool), [])
    world.add_movable("cart", np.array([[True, False], [True, True]]), (0, 0))
    assert world.movables["cart"].box == (0, 2, 0, 2)
    with pytest.raises(ValueError, match="already"):
        world.add_movable("cart", (1, 1), (5, 5))
    with pytest.raises(KeyError, match="cart"):
        world.move_movable("crate", (3, 3))
    with pytest.raises(ValueError, match="inside"):
        world.move_movable("cart", (9, 9))
    with pytest.raises(ValueError, match="True cell"):
        world.add_movable("ghost", np.zeros((2, 2), dtype=bool), (3, 3))
    assert world.movables["cart"].box == (0, 2, 0, 2) and world.occupied.sum() == 3


def test_a_door_leaf_closing_onto_a_robot_reports_it_and_lets_it_back_off() -> None:
    world = World(np.zeros((40, 40), dtype=bool), [2.0, 2.0])
    world.place_robots([(20.5, 20.0), (5.5, 5.5)])
    robot = world.query_filter(0, robots_block=False)
    change = world.add_movable("leaf", (10, 1), (15, 22))  # x in [22, 23): 0.5 into robot 0
    assert change.robots == (0,)
    assert world.blocked((20.5, 20.0), (22.0, 20.0), 2.0, robot) is not None  # into the leaf
    assert world.blocked((20.5, 20.0), (18.0, 20.0), 2.0, robot) is None  # backing off
    assert not world.move_movable("leaf", (15, 30)).robots


def test_a_robot_buried_by_a_collapse_cannot_move() -> None:
    world = World(np.zeros((40, 40), dtype=bool), [1.0])
    world.place_robots([(20.5, 20.5)])
    robot = world.query_filter(0, robots_block=False)
    change = world.set_cells((17, 24, 17, 24), True)
    assert change.robots == (0,) and world.buried((20.5, 20.5))
    for end in ((20.5, 25.0), (15.0, 20.5), (20.6, 20.5)):
        hit = world.blocked((20.5, 20.5), end, 1.0, robot)
        assert hit is not None and hit.alpha == 0.0
    world.set_cells((17, 24, 17, 24), False)
    assert world.blocked((20.5, 20.5), (20.5, 25.0), 1.0, robot) is None


def test_radio_wall_counts_and_line_of_sight_follow_a_closed_door(rooms: np.ndarray) -> None:
    world = World(rooms, [])
    a, b = np.array([[10.5, 30.5]]), np.array([[70.5, 30.5]])
    assert walls_between(world.occupied, a, b)[0][0] == 0
    assert world.first_hit((10.5, 30.5), (70.5, 30.5), 0.0, walls(world)) is None
    world.add_movable("door", (12, 2), (25, 40))
    runs, inside = walls_between(world.occupied, a, b)
    assert runs[0] == 1 and inside[0] == pytest.approx(2.0)
    hit = world.first_hit((10.5, 30.5), (70.5, 30.5), 0.0, walls(world))
    assert hit is not None and hit.point[0] == pytest.approx(40.0)


def test_a_move_clear_of_every_cell_and_body_skips_chipmunk_with_the_same_answer(
    rooms: np.ndarray,
) -> None:
    """``World.blocked`` answers "nothing" without asking Chipmunk when no occupied cell and
    no robot touches the swept box (``world/clearance.py``): over random short moves near
    walls, a movable cart, a door and other robots, it answers exactly what Chipmunk's
    query answers (the same hits, the same Nones), and the skip is taken for most moves."""
    world = World(rooms.copy(), [0.5, 0.5, 1.5])
    world.add_movable("cart", (3, 2), (20, 60))
    world.place_robots([(10.5, 10.5), (30.0, 45.25), (20.0, 20.0)])
    rng = np.random.default_rng(7)
    skipped = 0
    for _ in range(3000):
        start = (float(rng.uniform(1.5, 78.5)), float(rng.uniform(1.5, 58.5)))
        angle, length = rng.uniform(0, 2 * np.pi), rng.uniform(0.0, 3.0)
        end = (start[0] + length * np.cos(angle), start[1] + length * np.sin(angle))
        radius = float(rng.choice([0.0, 0.5, 1.0, 2.0]))
        shape_filter = world.query_filter(int(rng.integers(-1, 3)), bool(rng.integers(0, 2)))
        if world.buried(start):
            continue
        grid, circles = world.ray_targets(shape_filter)
        box = (min(start[0], end[0]) - radius, min(start[1], end[1]) - radius,
               max(start[0], end[0]) + radius, max(start[1], end[1]) + radius)  # fmt: skip
        clear = box_clear(grid, circles, *box)
        skipped += clear
        chipmunk = world.first_hit(start, end, max(radius - GRAZE, 0.0), shape_filter)
        if clear:
            assert chipmunk is None
        expected = chipmunk
        if chipmunk is not None and chipmunk.alpha <= 1e-9:  # a contact it moves away from
            along = chipmunk.normal[0] * (end[0] - start[0]) + chipmunk.normal[1] * (
                end[1] - start[1]
            )
            expected = None if along >= 0 else chipmunk
        assert world.blocked(start, end, radius, shape_filter) == expected
    assert skipped > 1000
