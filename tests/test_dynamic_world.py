"""The world as it changes: rays meet moving obstacles where they are, closed doors cut radio,
radio passes quiet obstacles, and no robot ever overlaps an obstacle or rubble."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mresim_phys.comms.base import Radios
from mresim_phys.comms.line_of_sight import LineOfSightComm
from mresim_phys.comms.params import LineOfSightParams
from mresim_phys.sim import Simulation
from mresim_phys.world.changes import circles_cover
from mresim_phys.world.doors import door_cells
from mresim_phys.world.element_params import DoorParams
from mresim_phys.world.space import World
from mresim_phys.world.walls import walls_between

ROOT_SCENARIOS = "scenarios"


def corridor() -> World:
    """A 40x120 map: a wall at x = 60 with a doorway at rows 15..25."""
    occupied = np.zeros((40, 120), dtype=bool)
    occupied[:, 60:62] = True
    occupied[15:25, 60:62] = False
    return World(occupied, [1.0])


def test_a_ray_hits_a_moving_obstacle_where_it_is_at_that_step() -> None:
    world = corridor()
    world.add_movable("cart", (4, 4), (18, 30))  # cells x 30..33, y 18..21
    walls = world.query_filter(None, robots_block=False)
    ray = world.cast_rays((10.5, 19.5), np.array([0.0]), 100.0, walls)
    assert ray.ranges[0] == pytest.approx(30 - 10.5)
    world.move_movable("cart", (18, 40))
    ray = world.cast_rays((10.5, 19.5), np.array([0.0]), 100.0, walls)
    assert ray.ranges[0] == pytest.approx(40 - 10.5)
    world.remove_movable("cart")
    ray = world.cast_rays((10.5, 19.5), np.array([0.0]), 100.0, walls)
    assert ray.ranges[0] == pytest.approx(100.0)  # through the doorway, nothing in the way


def test_a_closed_door_cuts_line_of_sight_and_path_loss_counts_it() -> None:
    world = corridor()
    radios = Radios.of([(40.5, 19.5), (80.5, 19.5)], [100.0, 100.0])
    sight = LineOfSightComm(LineOfSightParams())
    ends = np.array([[40.5, 19.5]]), np.array([[80.5, 19.5]])
    assert sight.links(radios, world)[0, 1]
    assert walls_between(world.radio_occupied, *ends)[0][0] == 0
    cells, at = door_cells(DoorParams(name="d", between=((61.0, 14.0), (61.0, 26.0))))
    world.add_movable("d", cells, at)
    assert not sight.links(radios, world)[0, 1]
    assert walls_between(world.radio_occupied, *ends)[0][0] == 1


def test_radio_passes_an_obstacle_that_does_not_block_it() -> None:
    world = corridor()
    radios = Radios.of([(40.5, 19.5), (80.5, 19.5)], [100.0, 100.0])
    sight = LineOfSightComm(LineOfSightParams())
    world.add_movable("person", (4, 4), (18, 50), blocks_radio=False)
    assert sight.links(radios, world)[0, 1]
    ends = np.array([[40.5, 19.5]]), np.array([[80.5, 19.5]])
    assert walls_between(world.radio_occupied, *ends)[0][0] == 0
    assert world.occupied[19, 51]  # ... while rays and motion meet it
    east = np.array([0.0])
    assert sight.reach(radios, 0, east, world)[0] == pytest.approx(120 - 40.5)  # map edge
    world.add_movable("crate", (4, 4), (18, 55))  # one that blocks radio
    assert sight.reach(radios, 0, east, world)[0] == pytest.approx(55 - 40.5)


def overlaps(sim: Simulation) -> list[str]:
    """Robots whose body overlaps an occupied cell of the truth."""
    hit = []
    for robot in sim.robots:
        x, y = robot.position
        reach = math.ceil(robot.radius) + 1
        r0, c0 = max(math.floor(y) - reach, 0), max(math.floor(x) - reach, 0)
        window = sim.world.occupied[r0 : math.floor(y) + reach + 1, c0 : math.floor(x) + reach + 1]
        cells = np.argwhere(window) + np.array([r0, c0])
        body = np.array([[x, y]]), np.array([robot.radius])
        if circles_cover(*body, cells).any():
            hit.append(robot.name)
    return hit


@pytest.mark.parametrize("seed", [1, 2, 3])
@pytest.mark.parametrize("scenario", ["14_office_people_doors", "15_office_collapse"])
def test_no_robot_ever_overlaps_an_obstacle_or_rubble(scenario: str, seed: int) -> None:
    sim = Simulation.from_yaml(f"{ROOT_SCENARIOS}/{scenario}.yaml", seed=seed, steps=250)
    for record in sim.iterate():
        assert overlaps(sim) == [], record.step
