"""Composition root: a validated :class:`Scenario` -> the parts of a simulation.

The only module that reads the schema and builds runtime objects: it loads the
ground-truth map, builds the pymunk world, checks every robot's start against
it, creates the agents with their strategies, planners and random streams, and
the comm model. Everything downstream takes these objects, never the Scenario.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from mresim_phys.agents import BASE_NAME, Agent, Robot, empty_belief
from mresim_phys.comms import COMM_MODELS, CommModel
from mresim_phys.errors import ScenarioError
from mresim_phys.knowledge.mapping import Coverage
from mresim_phys.planning import PLANNERS, Planner
from mresim_phys.rng import named_stream
from mresim_phys.scenario.readers import LoadedMap, load_image_map, load_ros_map, load_text_map
from mresim_phys.scenario.schema import MapSpec, RobotSpec, Scenario
from mresim_phys.strategies import STRATEGIES, Strategy
from mresim_phys.world.maps import free_components_mask
from mresim_phys.world.space import World


@dataclass
class Parts:
    """Everything a :class:`~mresim_phys.sim.Simulation` runs on."""

    truth: LoadedMap
    world: World
    base: Agent
    robots: list[Robot]
    comm: CommModel
    coverage: Coverage


def load_map(spec: MapSpec) -> LoadedMap:
    """Read the ground truth named by ``spec`` (paths already resolved)."""
    kind, path = spec.source
    if kind == "image":
        return load_image_map(Path(path), threshold=spec.threshold, negate=spec.negate)
    if kind == "grid":
        return load_text_map(Path(path))
    return load_ros_map(Path(path))


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


def check_base(world: World, scenario: Scenario) -> None:
    """The base station must stand inside the map."""
    rows, cols = world.shape
    x, y = scenario.base_station.position
    if not (0 <= x < cols and 0 <= y < rows):
        raise ScenarioError(
            f"base_station.position {[x, y]} is outside the {cols}x{rows} map;"
            " give 0 <= x < columns and 0 <= y < rows."
        )


def make_robot(spec: RobotSpec, index: int, seed: int, shape: tuple[int, int]) -> Robot:
    """A robot with an all-unknown map, its strategy, its planner and its own random stream."""
    belief, safe = empty_belief(shape)
    strategy: Strategy = STRATEGIES.make(spec.strategy.name, spec.strategy.params)
    planner: Planner = PLANNERS.make(spec.planner.name, spec.planner.params)
    return Robot(
        name=spec.name,
        index=index,
        position=(float(spec.start[0]), float(spec.start[1])),
        comm_range=spec.comm_range,
        belief=belief,
        safe=safe,
        role=spec.role,
        spec=spec,
        strategy=strategy,
        planner=planner,
        heading=math.radians(spec.heading_deg),
        rng=named_stream(seed, "strategy", index),
    )


def build_parts(scenario: Scenario) -> Parts:
    """Load the map and build world, agents, comm model and coverage counter."""
    truth = load_map(scenario.map)
    world = World(truth.occupied, [r.radius for r in scenario.robots])
    for spec in scenario.robots:
        check_start(world, spec)
    check_base(world, scenario)
    shape = truth.occupied.shape
    base_belief, base_safe = empty_belief(shape)
    base = Agent(
        name=BASE_NAME,
        index=0,
        position=tuple(map(float, scenario.base_station.position)),
        comm_range=scenario.base_station.comm_range,
        belief=base_belief,
        safe=base_safe,
        role="base",
    )
    robots = [make_robot(s, i + 1, scenario.seed, shape) for i, s in enumerate(scenario.robots)]
    world.place_robots([r.position for r in robots])
    reachable = free_components_mask(truth.occupied, [r.start for r in scenario.robots])
    comm: CommModel = COMM_MODELS.make(scenario.communication.model, scenario.communication.params)
    return Parts(truth, world, base, robots, comm, Coverage(reachable))
