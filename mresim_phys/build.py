"""Composition root (between input and runtime): a validated Scenario -> runtime values.

The only module that reads the schema and builds runtime objects: the ground
truth and the pymunk world, the team (bodies, lasers, strategies, planners; every
start checked against the world), the base station, the network with its
channels, the events, the coverage counter, the explorable area and the connected free
space it counts against, every named random
stream (one :class:`~mresim_phys.rng.Streams` per run) and the run rules. The
runtime (``sim``, motion, sensing, comms, strategies, metrics) takes these values
and never imports the schema, so a run can be rebuilt in any process from a
picklable Scenario alone. ``sim`` reaches the input side only through here
(``load_scenario`` is re-exported for ``Simulation.from_yaml``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from mresim_phys.agents import Agent, Body, Robot, empty_belief
from mresim_phys.build_world import (
    build_ground,
    build_prior,
    build_terrain,
    check_world_events,
    no_go_of,
    world_can_change,
)
from mresim_phys.clocks.feature import CLOCK, Clock
from mresim_phys.columns import TEAM_COLUMNS
from mresim_phys.comms import COMM_MODELS
from mresim_phys.comms.ledger import Ledger
from mresim_phys.comms.network import Channel, Network
from mresim_phys.comms.radio import build_layer
from mresim_phys.comms.radio_feature import RADIO, RadioCounters
from mresim_phys.comms.regions import RegionProbe
from mresim_phys.discovery_feature import give_discovery
from mresim_phys.faults.runtime import Faults, build_faults
from mresim_phys.ground.grid import Ground
from mresim_phys.knowledge.coverage import Coverage
from mresim_phys.knowledge.known_area import KNOWN_AREA, KnownArea
from mresim_phys.knowledge.latest import LatestCoverage, give_stamps
from mresim_phys.knowledge.teammates import BASE_NAME
from mresim_phys.localization.feature import LOCALIZATION, localize
from mresim_phys.localization.spec import LocalizationSpec
from mresim_phys.planning import PLANNERS
from mresim_phys.readings_feature import READINGS, ReadingCounts
from mresim_phys.rng import Streams
from mresim_phys.scenario.faults import localization_faults, robustness_columns
from mresim_phys.scenario.load import load_scenario
from mresim_phys.scenario.on_map import (
    check_apart,
    check_base,
    check_beacons,
    check_event_boxes,
    check_inside,
    load_map,
    overlapping,
)
from mresim_phys.scenario.readers import LoadedMap
from mresim_phys.scenario.run_specs import StartJitterSpec
from mresim_phys.scenario.schema import BaseStationSpec, RobotSpec, Scenario, SensorSpec
from mresim_phys.strategies import STRATEGIES
from mresim_phys.types import BeliefGrid, FloatArray, RobotSight
from mresim_phys.world.beam import Beam
from mresim_phys.world.debris import RandomDebris
from mresim_phys.world.doors import Door
from mresim_phys.world.elements import build_elements
from mresim_phys.world.event_api import Event
from mresim_phys.world.events import make_event
from mresim_phys.world.explorable import Explorable
from mresim_phys.world.obstacles import MovingObstacle
from mresim_phys.world.reach import Reachable
from mresim_phys.world.sensing import Laser
from mresim_phys.world.space import World
from mresim_phys.world.terrain import TerrainGrid

__all__ = ["RunRules", "Scenario", "Setup", "build_setup", "load_scenario", "region_probe"]


def check_start(world: World, robot: RobotSpec) -> None:
    """A robot must start inside the map, clear of every wall (the exact walls and
    obstacles of ``world``)."""
    check_inside(world.occupied, robot)
    if world.overlaps_wall(robot.start, robot.radius):
        raise overlapping(robot)


def laser_of(spec: SensorSpec) -> Laser:
    """The runtime laser of a sensor spec (its beam model, if it has one)."""
    beam = None if spec.beam is None else Beam(**spec.beam.model_dump())
    return Laser(spec.range, spec.fov_deg, spec.rays, spec.noise_std, spec.safe_fraction, beam)


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
        rng=streams.of_robot("strategy", spec.name),
        features={KNOWN_AREA.key: KnownArea()}
        | ({} if spec.sensor.beam is None else {READINGS.key: ReadingCounts.on(shape)}),
    )


def give_localization(
    team: list[Robot], scenario: Scenario, streams: Streams, shape: tuple[int, int]
) -> None:
    """The localisation state of each robot whose spec has one, or that a localisation
    fault may strike (then without drift), at its (jittered) start; its motion noise from
    its ``odometry`` stream, its corrections' from ``pose-fix``, a jump's from ``jump``."""
    struck = localization_faults(scenario)
    bounds = (float(shape[1]), float(shape[0]))
    for robot, spec in zip(team, scenario.robots, strict=True):
        block = spec.localization or (LocalizationSpec() if robot.name in struck else None)
        if block is not None:
            odometry, fixes, jumps = (
                streams.of_robot(s, robot.name) for s in ("odometry", "pose-fix", "jump")
            )
            pose = (*robot.position, robot.heading)
            state = localize(block, pose, (odometry, fixes, jumps), bounds)
            robot.features[LOCALIZATION.key] = state


def give_clocks(team: list[Robot], scenario: Scenario, streams: Streams) -> None:
    """The clock of each robot whose spec has one (``clocks/``); its drawn compute delays
    from its ``compute-delay`` stream."""
    for robot, spec in zip(team, scenario.robots, strict=True):
        if spec.clock is not None:
            rng = streams.of_robot("compute-delay", robot.name)
            robot.features[CLOCK.key] = Clock.of(spec.clock, rng)


def make_base(spec: BaseStationSpec, shape: tuple[int, int]) -> Agent:
    """The base station (agent index 0) with an all-unknown map."""
    belief, safe = empty_belief(shape)
    position = (float(spec.position[0]), float(spec.position[1]))
    return Agent(BASE_NAME, 0, position, spec.comm_range, belief, safe, role="base")


def make_team(
    robots: list[RobotSpec], streams: Streams, world: World, jitter: StartJitterSpec | None = None
) -> list[Robot]:
    """Every robot, checked against the world, shifted by ``jitter`` and placed in it."""
    for spec in robots:
        check_start(world, spec)
    team = [make_robot(s, i + 1, streams, world.shape) for i, s in enumerate(robots)]
    place_in_hierarchy(team, robots)
    if jitter is not None and (jitter.position > 0 or jitter.heading_deg > 0):
        for robot in team:
            jitter_start(robot, jitter, streams.of_robot("start-jitter", robot.name), world)
    world.place_robots([r.position for r in team])
    return team


def place_in_hierarchy(team: list[Robot], robots: list[RobotSpec]) -> None:
    """Each robot's parent, children and hops from the base (validated by the schema)."""
    parents = {spec.name: spec.parent for spec in robots}
    for robot in team:
        robot.parent = parents[robot.name]
        robot.children = tuple(sorted(n for n, p in parents.items() if p == robot.name))
        hops, at = 0, robot.parent
        while at is not None and at != "base":
            hops, at = hops + 1, parents[at]
        robot.hops = hops + 1 if at == "base" else 0


JITTER_TRIES = 100  # draws of a shifted start before the declared one is kept


def jitter_start(
    robot: Robot, jitter: StartJitterSpec, rng: np.random.Generator, world: World
) -> None:
    """Shift ``robot``'s start by at most ``jitter.position`` (uniform in a disk, reachable
    in a straight line without touching a wall) and turn it by at most
    ``jitter.heading_deg``, both from the robot's own stream."""
    robot.heading += math.radians(float(rng.uniform(-jitter.heading_deg, jitter.heading_deg)))
    start = robot.position
    walls_only = world.query_filter(None, robots_block=False)
    for _ in range(JITTER_TRIES if jitter.position > 0 else 0):
        r = jitter.position * math.sqrt(float(rng.random()))
        a = float(rng.uniform(0.0, 2.0 * math.pi))
        end = (start[0] + r * math.cos(a), start[1] + r * math.sin(a))
        clear = world.blocked(start, end, robot.radius, walls_only) is None
        if clear and not world.overlaps_wall(end, robot.radius):
            robot.position = end
            return


def team_order(robots: list[RobotSpec], streams: Streams, vary: bool) -> tuple[str, ...]:
    """The robots' tie-break order in auctions: a seeded permutation of the sorted names, or
    the sorted names themselves; either way the order the team is listed in does not matter."""
    names = sorted(r.name for r in robots)
    if not vary:
        return tuple(names)
    return tuple(names[int(i)] for i in streams.get("tie-order").permutation(len(names)))


def radio_ranges(scenario: Scenario) -> tuple[FloatArray, FloatArray]:
    """Every agent's main-channel range and transmit power (NaN: the model's default)."""
    radios: list[BaseStationSpec | RobotSpec] = [scenario.base_station, *scenario.robots]
    ranges = np.array([r.comm_range for r in radios], dtype=np.float64)
    powers = np.array(
        [np.nan if r.comm_power_dbm is None else r.comm_power_dbm for r in radios],
        dtype=np.float64,
    )
    return ranges, powers


def build_network(
    scenario: Scenario, streams: Streams, shape: tuple[int, int], latest: bool = False
) -> Network:
    """The communication phase of ``scenario``: its channels, ledger and exchange rules."""
    spec = scenario.communication
    ranges, powers = radio_ranges(scenario)
    model = COMM_MODELS.make(spec.model, spec.params)
    names = [BASE_NAME, *(r.name for r in scenario.robots)]
    main = Channel("main", model, ranges, powers, spec.dropout, streams.get("dropout-main"))
    main.radio = build_layer(spec, "main", names, shape, streams.get)
    control = None
    if spec.control is not None:
        c = spec.control
        control = Channel(
            "control",
            COMM_MODELS.make(c.model, c.params),
            np.full(len(ranges), c.range),
            powers,
            c.dropout,
            streams.get("dropout-control"),
        )
        control.radio = build_layer(c, "control", names, shape, streams.get)
    return Network(
        main,
        Ledger(shape, len(ranges), latest),
        control=control,
        multi_hop=scenario.simulation.multi_hop,
        full_maps=spec.maps == "full",
    )


def region_probe(scenario: Scenario, world: World) -> RegionProbe:
    """The probe of ``scenario``'s main channel on ``world`` (live runs and replays)."""
    comm = scenario.communication
    ranges, powers = radio_ranges(scenario)
    return RegionProbe(COMM_MODELS.make(comm.model, comm.params), ranges, powers, world)


@dataclass(frozen=True)
class RunRules:
    """How the cycle runs and when it stops."""

    steps: int  # hard cap
    scan_every_point: bool  # scan after every path point (the original) or once per step
    robots_block: bool  # robots block each other's rays and motion
    stop_explored: float | None = None
    stop_known_at_base: float | None = None
    stop_all_done: bool = True
    stalled_for: int | None = None  # stop after this many steps without progress
    stalled_gain: float = 0.001  # the smallest gain that counts as progress
    presume_lost_after: int = 200  # steps of silence after which a teammate is presumed lost
    vary_with_seed: bool = True  # the seed varies initial random steps, ties and starts
    latest: bool = False  # beliefs hold each cell's latest observation (a changing world)
    fault_columns: bool = False  # metrics.csv has the robustness columns (scenario.faults)


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
    explorable: Explorable  # what the team can see from where it can go, followed likewise
    events: list[Event]
    streams: Streams
    rules: RunRules
    starts: list[tuple[float, float]]  # where the robots started (the reachable set's seeds)
    resolution: float | None  # metres per cell, for reports
    team_order: tuple[str, ...] = ()  # tie-break order of the robots in auctions
    free_area: int = 0  # explorable cells at the start: the done rule's building, known to robots
    elements: list[MovingObstacle | Door | RandomDebris] = field(default_factory=list)
    terrain: TerrainGrid | None = None  # true speed factor per cell; None: no terrain
    ground: Ground | None = None  # true ground classes (ground/); None: none
    prior: BeliefGrid | None = None  # the prior map the listed robots start with; None: none
    faults: Faults | None = None  # random failures, batteries, hazard zones; None: none

    def sensing_streams(self) -> list[np.random.Generator]:
        """Each robot's laser-noise stream, in robot order."""
        return [self.streams.of_robot("sensing", r.name) for r in self.robots]

    def event_streams(self) -> list[np.random.Generator]:
        """Each event's own stream, in scenario order."""
        return [self.streams.get("event", k) for k in range(len(self.events))]


def explorable_area(
    occupied: np.ndarray, robots: list[Robot], ground: Ground | None = None
) -> Explorable:
    """The explorable area of ``robots`` from where they start (after any jitter), where a
    robot may stand (not on ground no robot crosses)."""
    sights = [RobotSight(r.position, r.radius, r.laser.range) for r in robots]
    return Explorable(occupied, sights, no_go_of(ground, robots))


def run_rules(scenario: Scenario) -> RunRules:
    """The scenario's cycle and stop rules as plain values."""
    sim, stop = scenario.simulation, scenario.stop
    latest = sim.belief == "latest" or (sim.belief == "auto" and world_can_change(scenario))
    return RunRules(
        steps=scenario.steps,
        scan_every_point=sim.scan == "point",
        robots_block=sim.robots_block,
        stop_explored=stop.explored,
        stop_known_at_base=stop.known_at_base,
        stop_all_done=stop.all_done,
        stalled_for=stop.stalled_for,
        stalled_gain=stop.stalled_gain,
        presume_lost_after=sim.presume_lost_after,
        vary_with_seed=sim.vary_with_seed,
        latest=latest,
        fault_columns=robustness_columns(scenario),
    )


def build_setup(scenario: Scenario) -> Setup:
    """Load the map and build everything a run of ``scenario`` needs."""
    truth = load_map(scenario.map)
    world = World(truth.occupied, [r.radius for r in scenario.robots])
    streams = Streams(scenario.seed)
    vary = scenario.simulation.vary_with_seed
    jitter = scenario.simulation.start_jitter if vary else None
    robots = make_team(scenario.robots, streams, world, jitter)
    if scenario.simulation.robots_block:
        check_apart(scenario.robots)
    check_base(world.occupied, scenario.base_station)
    check_beacons(world.occupied, scenario.robots)
    give_localization(robots, scenario, streams, world.shape)
    give_clocks(robots, scenario, streams)
    if scenario.metrics.team or set(TEAM_COLUMNS) & set(scenario.metrics.columns):
        give_discovery(robots, world.shape)
    starts = [r.position for r in robots]
    events = [make_event(e) for e in scenario.events]
    check_event_boxes(scenario, world.shape)
    check_world_events(scenario, events, world)
    bodies = np.array([(*r.position, r.radius) for r in robots], dtype=np.float64)
    elements = build_elements(
        scenario.obstacles, scenario.doors, scenario.random_debris, world, streams, bodies
    )
    crosses = [spec.crosses for spec in scenario.robots]
    ground = build_ground(scenario.ground, robots, crosses, world.shape)
    reachable = Reachable(truth.occupied, starts)
    explorable = explorable_area(truth.occupied, robots, ground)
    rules = run_rules(scenario)
    base = make_base(scenario.base_station, world.shape)
    if rules.latest:
        for agent in [base, *robots]:
            give_stamps(agent.features, world.shape)
    terrain = build_terrain(scenario.terrain, robots, world)
    prior = build_prior(scenario.prior, robots, world.shape, streams)
    network = build_network(scenario, streams, world.shape, rules.latest)
    if network.bounded:
        for robot in robots:
            robot.features[RADIO.key] = RadioCounters()
    return Setup(
        truth=truth,
        world=world,
        base=base,
        robots=robots,
        network=network,
        coverage=(
            LatestCoverage(explorable.mask, world.occupied, reachable.mask)
            if rules.latest
            else Coverage(explorable.mask, reachable.mask)
        ),
        reachable=reachable,
        explorable=explorable,
        events=events,
        streams=streams,
        rules=rules,
        starts=starts,
        resolution=scenario.map.resolution or truth.resolution,
        team_order=team_order(scenario.robots, streams, vary),
        free_area=int(np.count_nonzero(explorable.mask)),
        elements=elements,
        terrain=terrain,
        ground=ground,
        prior=prior,
        faults=build_faults(scenario.faults, robots, world.shape, streams),
    )
