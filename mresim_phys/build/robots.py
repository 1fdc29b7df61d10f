"""Composition root, team: robot specs -> robots with bodies, lasers, plugins and streams.

Checks every start against the true world first, so a robot inside a wall is a
readable error naming the robot before anything runs.
"""

from __future__ import annotations

import math

from mresim_phys.agents import Agent, Body, Robot, empty_belief
from mresim_phys.errors import ScenarioError
from mresim_phys.knowledge.teammates import BASE_NAME
from mresim_phys.planning import PLANNERS
from mresim_phys.rng import Streams
from mresim_phys.scenario.schema import BaseStationSpec, RobotSpec, SensorSpec
from mresim_phys.strategies import STRATEGIES
from mresim_phys.world.sensing import Laser
from mresim_phys.world.space import World


def check_start(world: World, robot: RobotSpec) -> None:
    """A robot must start inside the map, clear of every wall."""
    rows, cols = world.shape
    x, y = robot.start
    if not (0 <= x < cols and 0 <= y < rows):
        raise ScenarioError(
            f"robot {robot.name!r} starts at {list(robot.start)}, outside the {cols}x{rows} map;"
            " give a start with 0 <= x < columns and 0 <= y < rows (x = column, y = row)."
        )
    if world.overlaps_wall(robot.start, robot.radius):
        raise ScenarioError(
            f"robot {robot.name!r} starts at {list(robot.start)} inside or overlapping a wall"
            f" (radius {robot.radius}); move its start into free space at least its radius"
            " away from any obstacle."
        )


def check_base(world: World, base: BaseStationSpec) -> None:
    """The base station must stand inside the map."""
    rows, cols = world.shape
    x, y = base.position
    if not (0 <= x < cols and 0 <= y < rows):
        raise ScenarioError(
            f"base_station.position {[x, y]} is outside the {cols}x{rows} map;"
            " give 0 <= x < columns and 0 <= y < rows."
        )


def laser_of(spec: SensorSpec) -> Laser:
    """The runtime laser of a sensor spec."""
    return Laser(spec.range, spec.fov_deg, spec.rays, spec.noise_std, spec.safe_fraction)


def body_of(spec: RobotSpec) -> Body:
    """The runtime body of a robot spec."""
    return Body(spec.speed, spec.radius, spec.wall_margin, laser_of(spec.sensor))


def make_robot(spec: RobotSpec, index: int, streams: Streams, shape: tuple[int, int]) -> Robot:
    """A robot with an all-unknown map, its strategy, its planner and its own random stream."""
    belief, safe = empty_belief(shape)
    return Robot(
        name=spec.name,
        index=index,
        position=(float(spec.start[0]), float(spec.start[1])),
        comm_range=spec.comm_range,
        belief=belief,
        safe=safe,
        role=spec.role,
        body=body_of(spec),
        strategy=STRATEGIES.make(spec.strategy.name, spec.strategy.params),
        planner=PLANNERS.make(spec.planner.name, spec.planner.params),
        heading=math.radians(spec.heading_deg),
        rng=streams.get("strategy", index),
    )


def make_base(spec: BaseStationSpec, shape: tuple[int, int]) -> Agent:
    """The base station (agent index 0) with an all-unknown map."""
    belief, safe = empty_belief(shape)
    position = (float(spec.position[0]), float(spec.position[1]))
    return Agent(BASE_NAME, 0, position, spec.comm_range, belief, safe, role="base")


def make_team(robots: list[RobotSpec], streams: Streams, world: World) -> list[Robot]:
    """Every robot, checked against the world and placed in it."""
    for spec in robots:
        check_start(world, spec)
    team = [make_robot(s, i + 1, streams, world.shape) for i, s in enumerate(robots)]
    world.place_robots([r.position for r in team])
    return team
