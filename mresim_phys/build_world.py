"""Composition root, the world's part: the world's events and layers checked and built.

Read by ``build.py`` only: the checks of events that need the map, whether anything in
the scenario changes the truth during the run, the true terrain and the degraded prior
map the listed robots start with. Each turns a user mistake into a ScenarioError naming the field.
"""

from __future__ import annotations

from mresim_phys.agents import Robot
from mresim_phys.errors import ScenarioError
from mresim_phys.ground.feature import GROUND
from mresim_phys.ground.grid import Access, Ground, ground_of
from mresim_phys.ground.spec import GroundSpec
from mresim_phys.knowledge.prior import PRIOR, prior_belief
from mresim_phys.knowledge.prior import STREAM as PRIOR_STREAM
from mresim_phys.knowledge.terrain import TERRAIN, unknown_terrain
from mresim_phys.rng import Streams
from mresim_phys.scenario.maps import PriorSpec
from mresim_phys.scenario.on_map import check_door_names, load_map
from mresim_phys.scenario.schema import (
    Scenario,
)
from mresim_phys.types import BeliefGrid, BoolGrid
from mresim_phys.world.element_params import TerrainSpec
from mresim_phys.world.event_api import Event, NeedsMap
from mresim_phys.world.space import World
from mresim_phys.world.terrain import TerrainGrid, terrain_grid


def check_world_events(scenario: Scenario, events: list[Event], world: World) -> None:
    """Doors the events name must exist; an event that needs the map works out where it
    acts now, once (a collapse region must lie on the map)."""
    check_door_names(scenario)
    for i, event in enumerate(events):
        kind = event.name
        if isinstance(event, NeedsMap):
            try:
                event.prepare(world.shape)
            except ValueError as exc:
                raise ScenarioError(f"events[{i}].{kind}: {exc}") from None


def world_can_change(scenario: Scenario) -> bool:
    """Whether anything in the scenario changes the truth during the run."""
    events = any("world" in e.changes for e in scenario.events)
    return bool(scenario.obstacles or scenario.doors or scenario.random_debris or events)


def build_terrain(
    spec: TerrainSpec | None, robots: list[Robot], world: World
) -> TerrainGrid | None:
    """The true terrain grid (a ScenarioError naming the field if it cannot be built); each
    robot starts knowing none of it."""
    try:
        truth = terrain_grid(spec, world.shape)
    except ValueError as exc:
        raise ScenarioError(str(exc)) from None
    for robot in robots:
        known = unknown_terrain(truth)
        if known is not None:
            robot.features[TERRAIN.key] = known
    return truth


def build_ground(
    spec: GroundSpec | None,
    robots: list[Robot],
    crosses: list[dict[str, float] | None],
    shape: tuple[int, int],
) -> Ground | None:
    """The true ground classes (a ScenarioError naming the field if they cannot be built);
    each robot's access to them, from its ``crosses`` (``ground/``)."""
    try:
        ground = ground_of(spec, shape)
    except ValueError as exc:
        raise ScenarioError(str(exc)) from None
    if ground is not None:
        for robot, own in zip(robots, crosses, strict=True):
            robot.features[GROUND.key] = Access.of(ground, own)
    return ground


def no_go_of(ground: Ground | None, robots: list[Robot]) -> BoolGrid | None:
    """The cells no robot may enter (ground every robot is barred from; None: none)."""
    if ground is None:
        return None
    access = [GROUND.state_of(r.features) for r in robots]
    return ground.no_go([a.factors for a in access if a is not None])


def build_prior(
    spec: PriorSpec | None, robots: list[Robot], shape: tuple[int, int], streams: Streams
) -> BeliefGrid | None:
    """The degraded prior map (``knowledge/prior.py``), given to the robots it lists; a
    ScenarioError naming ``prior.map`` if it is not of the map's size."""
    if spec is None:
        return None
    loaded = load_map(spec.map)
    if loaded.occupied.shape != shape:
        (rows, cols), (prows, pcols) = shape, loaded.occupied.shape
        raise ScenarioError(
            f"prior.map.{spec.map.source[0]}: the prior map is {pcols}x{prows} cells but the map"
            f" is {cols}x{rows}; give a prior map of the map's size (the same building)."
        )
    grid = prior_belief(loaded.occupied, spec.drop, spec.flip, streams.get(PRIOR_STREAM))
    for robot in robots:
        if spec.robots == "all" or robot.name in spec.robots:
            robot.features[PRIOR.key] = grid
    return grid
