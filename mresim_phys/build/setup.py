"""Composition root: a validated :class:`Scenario` -> the plain runtime values of a run.

The only place that reads the schema and builds runtime objects: the ground
truth and the pymunk world, the team (bodies, lasers, strategies, planners), the
base station, the network with its channels, the events, the coverage counter,
every named random stream (one :class:`~mresim_phys.rng.Streams` per run) and the
run rules. The runtime (``sim``, motion, sensing, comms, strategies, metrics)
takes these values and never imports the schema, so a run can be rebuilt in any
process from a picklable Scenario alone.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mresim_phys.agents import Agent, Robot
from mresim_phys.build.network import build_network
from mresim_phys.build.robots import check_base, make_base, make_team
from mresim_phys.comms.network import Network
from mresim_phys.errors import ScenarioError
from mresim_phys.knowledge.mapping import Coverage
from mresim_phys.rng import Streams
from mresim_phys.scenario.readers import LoadedMap, load_image_map, load_ros_map, load_text_map
from mresim_phys.scenario.schema import MapSpec, Scenario
from mresim_phys.world.events import Event, make_event
from mresim_phys.world.reach import Reachable
from mresim_phys.world.space import World


@dataclass(frozen=True)
class RunRules:
    """How the cycle runs and when it stops."""

    steps: int  # hard cap
    scan_every_point: bool  # scan after every path point (the original) or once per step
    robots_block: bool  # robots block each other's rays and motion
    stop_explored: float | None = None
    stop_known_at_base: float | None = None
    stop_all_done: bool = True
    presume_lost_after: int = 200  # steps of silence after which a teammate is presumed lost


@dataclass
class Setup:
    """Everything a :class:`~mresim_phys.sim.Simulation` runs on."""

    truth: LoadedMap
    world: World
    base: Agent
    robots: list[Robot]
    network: Network
    coverage: Coverage
    reachable: Reachable  # free space connected to the starts, followed across world changes
    events: list[Event]
    streams: Streams
    rules: RunRules
    starts: list[tuple[float, float]]  # where the robots started (the reachable set's seeds)
    resolution: float | None  # metres per cell, for reports

    def sensing_streams(self) -> list[np.random.Generator]:
        """Each robot's laser-noise stream, in robot order."""
        return [self.streams.get("sensing", r.index) for r in self.robots]

    def event_streams(self) -> list[np.random.Generator]:
        """Each event's own stream, in scenario order."""
        return [self.streams.get("event", k) for k in range(len(self.events))]


def load_map(spec: MapSpec) -> LoadedMap:
    """Read the ground truth named by ``spec`` (paths already resolved)."""
    kind, path = spec.source
    if kind == "image":
        return load_image_map(Path(path), threshold=spec.threshold, negate=spec.negate)
    if kind == "grid":
        return load_text_map(Path(path))
    return load_ros_map(Path(path))


def check_event_boxes(scenario: Scenario, world: World) -> None:
    """Every map window an event names must lie inside the map."""
    rows, cols = world.shape
    for i, event in enumerate(scenario.events):
        for where, (row0, row1, col0, col1) in event.boxes():
            if not (0 <= row0 < row1 <= rows and 0 <= col0 < col1 <= cols):
                raise ScenarioError(
                    f"events[{i}].{where}: the window x {col0}..{col1}, y {row0}..{row1} is not"
                    f" inside the {cols}x{rows} map; give 0 <= x0 < x1 <= {cols} and"
                    f" 0 <= y0 < y1 <= {rows}."
                )


def run_rules(scenario: Scenario) -> RunRules:
    """The scenario's cycle and stop rules as plain values."""
    sim, stop = scenario.simulation, scenario.stop
    return RunRules(
        steps=scenario.steps,
        scan_every_point=sim.scan == "point",
        robots_block=sim.robots_block,
        stop_explored=stop.explored,
        stop_known_at_base=stop.known_at_base,
        stop_all_done=stop.all_done,
        presume_lost_after=sim.presume_lost_after,
    )


def build_setup(scenario: Scenario) -> Setup:
    """Load the map and build everything a run of ``scenario`` needs."""
    truth = load_map(scenario.map)
    world = World(truth.occupied, [r.radius for r in scenario.robots])
    streams = Streams(scenario.seed)
    robots = make_team(scenario.robots, streams, world)
    check_base(world, scenario.base_station)
    starts = [(float(r.start[0]), float(r.start[1])) for r in scenario.robots]
    events = [make_event(e) for e in scenario.events]
    check_event_boxes(scenario, world)
    reachable = Reachable(truth.occupied, starts)
    return Setup(
        truth=truth,
        world=world,
        base=make_base(scenario.base_station, world.shape),
        robots=robots,
        network=build_network(scenario, streams, world.shape),
        coverage=Coverage(reachable.mask),
        reachable=reachable,
        events=events,
        streams=streams,
        rules=run_rules(scenario),
        starts=starts,
        resolution=scenario.map.resolution or truth.resolution,
    )
