"""Moving obstacles, doors and debris as pieces: shapes as cells, motions, the wait rule."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mresim_phys.types import BoolGrid
from mresim_phys.world.debris import square_at
from mresim_phys.world.doors import Door, door_cells, line_cells
from mresim_phys.world.element_params import DoorParams, ObstacleParams
from mresim_phys.world.footprints import body_cells, region_cells
from mresim_phys.world.obstacles import MovingObstacle, advance
from mresim_phys.world.shapes import BoxShape, CircleRegion, CircleShape, PolygonShape


def test_a_circle_body_holds_the_cells_whose_centres_are_inside() -> None:
    cells, (row, col) = body_cells(CircleShape(circle=3.0))
    assert cells.sum() == 29  # centre offsets with dx^2 + dy^2 <= 9
    assert cells[row, col] and cells.shape == (7, 7) and (row, col) == (3, 3)
    assert np.array_equal(cells, cells[::-1]) and np.array_equal(cells, cells.T)


def test_a_box_w_cells_wide_covers_w_cells_and_tiny_shapes_keep_their_cell() -> None:
    cells, _ = body_cells(BoxShape(box=(6.0, 4.0)))
    assert cells.shape == (4, 6) and cells.all()
    tiny, at = body_cells(CircleShape(circle=0.1))
    assert tiny.sum() == 1 and tiny[at]


def test_a_polygon_body_is_relative_to_its_centre() -> None:
    cells, (_, col) = body_cells(PolygonShape(polygon=[(0, -1), (4, -1), (4, 1), (0, 1)]))
    _, cols = np.nonzero(cells)
    assert cols.min() == col and 3 <= cols.max() - col <= 4  # dx 0..3 inside, 4 on the edge


def test_circle_region_on_the_map() -> None:
    mask = region_cells(CircleRegion(circle=(10.0, 5.0, 2.0)), (20, 30))
    assert mask[4:6, 9:11].all() and mask.sum() == 12
    with pytest.raises(ValueError, match="covers no cell"):
        region_cells(CircleRegion(circle=(100.0, 100.0, 2.0)), (20, 30))


@pytest.mark.parametrize("end", [(17.3, 9.8), (2.2, 14.1), (9.5, 0.4), (3.5, 3.5)])
def test_door_lines_are_four_connected(end: tuple[float, float]) -> None:
    cells = np.array(line_cells((3.5, 3.5), end))
    steps = np.abs(np.diff(cells, axis=0)).sum(axis=1)
    assert (steps == 1).all()
    assert tuple(cells[-1]) == (math.floor(end[1]), math.floor(end[0]))


def test_a_diagonal_door_seals_its_doorway() -> None:
    params = DoorParams(name="d", between=((2.0, 2.0), (9.0, 8.0)))
    cells, (row0, col0) = door_cells(params)
    grid = np.zeros((12, 12), dtype=bool)
    grid[row0 : row0 + cells.shape[0], col0 : col0 + cells.shape[1]] = cells
    for row, col in line_cells((2.0, 2.0), (9.0, 8.0)):
        assert grid[row, col]


def test_periodic_door_state() -> None:
    door = DoorParams(name="d", between=((0, 0), (0, 5)), period=10, open_for=4, offset=2)
    states = [door.wanted_closed(step, False) for step in range(2, 14)]
    assert states == [False] * 4 + [True] * 6 + [False] * 2
    assert not door.wanted_closed(1, False) and door.wanted_closed(1, True)


@pytest.mark.parametrize(
    ("mode", "expected"),
    [
        ("loop", (10 - 12 / 2**0.5, 10 - 12 / 2**0.5)),
        ("back_and_forth", (8.0, 0.0)),
        ("once", (10.0, 10.0)),
    ],
)
def test_waypoint_modes(mode: str, expected: tuple[float, float]) -> None:
    points = [(0.0, 0.0), (10.0, 0.0), (10.0, 10.0)]
    # 32 cells: loop heads back to the first point along the diagonal, back_and_forth
    # turns at the end and comes back down both legs to 2 cells short of the start, once
    # stops at the end
    position, target, _ = advance(points, (0.0, 0.0), 1, 32.0, mode, 1)
    assert position == pytest.approx(expected)
    assert (target == -1) == (mode == "once")


class FakeWorld:
    """A world that refuses footprints touching ``blocked`` cells."""

    def __init__(self, blocked: BoolGrid) -> None:
        self.blocked, self.step, self.lines = blocked, 0, []
        self.placed: dict[str, tuple[int, int]] = {}

    def place_obstacle(self, name, footprint, at, blocks_radio=True, over_walls=False) -> bool:
        row, col = at
        h, w = footprint.shape
        if row < 0 or col < 0 or row + h > self.blocked.shape[0] or col + w > self.blocked.shape[1]:
            return False
        if (self.blocked[row : row + h, col : col + w] & footprint).any():
            return False
        self.placed[name] = at
        return True

    def remove_obstacle(self, name: str) -> None:
        del self.placed[name]

    def log(self, line: str) -> None:
        self.lines.append(line)


def test_an_obstacle_waits_while_its_way_is_blocked() -> None:
    blocked = np.zeros((20, 40), dtype=bool)
    params = ObstacleParams.model_validate(
        {
            "name": "p",
            "shape": {"circle": 1},
            "motion": {"waypoints": [[5.5, 10.5], [30.5, 10.5]], "speed": 2},
        }
    )
    obstacle = MovingObstacle(params, np.random.default_rng(0))
    world = FakeWorld(blocked)
    obstacle.apply(world)  # appears
    assert world.placed["p"] == (9, 4) and world.lines == ["obstacle p appears"]
    blocked[9:12, 7] = True  # something in the way two cells ahead
    for step in range(1, 4):
        world.step = step
        obstacle.apply(world)
    assert obstacle.position == pytest.approx((5.5, 10.5))  # one cell would touch column 7
    blocked[9:12, 7] = False
    world.step = 4
    obstacle.apply(world)
    assert obstacle.position == pytest.approx((7.5, 10.5)) and world.placed["p"] == (9, 6)


def test_a_random_walk_depends_only_on_its_stream() -> None:
    params = ObstacleParams.model_validate(
        {"name": "w", "shape": {"box": [2, 2]}, "motion": {"random_walk": [20, 10], "speed": 1.5}}
    )

    def walk(seed: int) -> list[tuple[float, float]]:
        obstacle, world = (
            MovingObstacle(params, np.random.default_rng(seed)),
            FakeWorld(np.zeros((20, 40), bool)),
        )
        out = []
        for step in range(30):
            world.step = step
            obstacle.apply(world)
            out.append(obstacle.position)
        return out

    assert walk(3) == walk(3) and walk(3) != walk(4)


def test_a_door_waits_for_its_doorway_to_clear() -> None:
    blocked = np.zeros((10, 10), dtype=bool)
    door = Door(DoorParams(name="d", between=((2.0, 5.5), (8.0, 5.5))))
    world = FakeWorld(blocked)
    door.apply(world)
    assert not door.closed and world.lines == []
    door.scheduled = True
    blocked[5, 4] = True  # a robot in the doorway
    door.apply(world)
    assert not door.closed
    blocked[5, 4] = False
    door.apply(world)
    assert door.closed and world.lines == ["door d closed"]
    door.scheduled = False
    door.apply(world)
    assert not door.closed and "d" not in world.placed


def test_debris_squares_are_clipped_to_the_map() -> None:
    mask = square_at((10, 10), 0, 9, 4)
    assert mask.sum() == 3 * 2 and mask[0:3, 8:10].all()


def test_a_misspelt_shape_key_names_the_kinds() -> None:
    from pydantic import ValidationError

    with pytest.raises(ValidationError) as info:
        ObstacleParams.model_validate(
            {"name": "x", "shape": {"circel": 3}, "motion": {"still": [1, 1]}}
        )
    errors = info.value.errors()
    assert len(errors) == 1 and "'circle' or 'box' or 'polygon'" in errors[0]["msg"]
