"""Composition root, the world's part: the truth map, the world's events and layers checked.

Read by ``build.py`` only: the ground truth from its file (``load_map``), the checks of
events that name map windows and doors, whether anything in the scenario changes the
truth during the run, the true terrain and the degraded prior map the listed robots
start with. Each turns a user mistake into a ScenarioError naming the field.
"""

from __future__ import annotations

from pathlib import Path

from mresim_phys.agents import Robot
from mresim_phys.errors import ScenarioError
from mresim_phys.knowledge.prior import STREAM as PRIOR_STREAM
from mresim_phys.knowledge.prior import prior_belief
from mresim_phys.knowledge.terrain import unknown_terrain
from mresim_phys.rng import Streams
from mresim_phys.scenario.maps import MapSpec, PriorSpec
from mresim_phys.scenario.readers import LoadedMap, load_image_map, load_ros_map, load_text_map
from mresim_phys.scenario.schema import (
    Scenario,
)
from mresim_phys.types import BeliefGrid
from mresim_phys.world.events import Event, NeedsMap
from mresim_phys.world.space import World
from mresim_phys.world.terrain import TerrainGrid, TerrainSpec, terrain_grid


def load_map(spec: MapSpec) -> LoadedMap:
    """Read the ground truth named by ``spec`` (paths already resolved)."""
    kind, path = spec.source
    if kind == "image":
        return load_image_map(Path(path), spec.threshold, spec.negate, spec.max_cells)
    if kind == "grid":
        return load_text_map(Path(path), spec.max_cells)
    return load_ros_map(Path(path), spec.max_cells)


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


def check_world_events(scenario: Scenario, events: list[Event], world: World) -> None:
    """Doors the events name must exist; an event that needs the map works out where it
    acts now, once (a collapse region must lie on the map)."""
    doors = {d.name for d in scenario.doors}
    for i, (params, event) in enumerate(zip(scenario.events, events, strict=True)):
        for where, door in params.doors():
            if door not in doors:
                known = ", ".join(sorted(doors)) or "none: add a 'doors' list"
                raise ScenarioError(
                    f"events[{i}].{where}: there is no door called {door!r} (doors: {known})."
                )
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
        robot.terrain = unknown_terrain(truth)
    return truth


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
            robot.prior = grid
    return grid
