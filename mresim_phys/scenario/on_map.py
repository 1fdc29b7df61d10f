"""A scenario on its map (phase 0, input): the ground truth read, and what its grid alone checks.

``load_map`` reads the map a scenario names. The checks here need the map's grid only (no
pymunk world): every start inside the map and on a free cell, the base station on a free
cell, no two bodies overlapping at their starts when robots block each other, every map
window an event names inside the map, and every door an event names in the doors list.
``mresim validate`` runs them without importing the simulator; building a run
(``build.py``) runs them too, then checks each start's clearance against the exact walls.
Each turns a user mistake into a ScenarioError naming the field.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from mresim_phys.errors import ScenarioError
from mresim_phys.scenario.maps import MapSpec
from mresim_phys.scenario.readers import LoadedMap, load_image_map, load_ros_map, load_text_map
from mresim_phys.scenario.schema import BaseStationSpec, RobotSpec, Scenario
from mresim_phys.types import BoolGrid


def check_on_map(scenario: Scenario) -> LoadedMap:
    """The scenario's map, read, with every check of this module passed."""
    truth = load_map(scenario.map)
    for robot in scenario.robots:
        check_inside(truth.occupied, robot)
    if scenario.simulation.robots_block:
        check_apart(scenario.robots)
    check_base(truth.occupied, scenario.base_station)
    check_beacons(truth.occupied, scenario.robots)
    check_event_boxes(scenario, truth.occupied.shape)
    check_door_names(scenario)
    return truth


def check_beacons(occupied: BoolGrid, robots: list[RobotSpec]) -> None:
    """Every localisation beacon stands inside the map, on a free cell."""
    for i, robot in enumerate(robots):
        corrections = robot.localization.corrections if robot.localization else []
        for k, fix in enumerate(corrections):
            for j, point in enumerate(fix.positions if fix.kind == "beacons" else []):
                where = f"robots[{i}] ({robot.name}).localization.corrections[{k}].positions[{j}]"
                check_free_cell(occupied, where, point, "put the beacon in free space")


def load_map(spec: MapSpec) -> LoadedMap:
    """Read the ground truth named by ``spec`` (paths already resolved)."""
    kind, path = spec.source
    if kind == "image":
        return load_image_map(Path(path), spec.threshold, spec.negate, spec.max_cells)
    if kind == "grid":
        return load_text_map(Path(path), spec.max_cells)
    return load_ros_map(Path(path), spec.max_cells)


def check_inside(occupied: BoolGrid, robot: RobotSpec) -> None:
    """A robot must start inside the map, on a free cell (its clearance from the walls is
    checked against the exact world when the run is built)."""
    rows, cols = occupied.shape
    x, y = robot.start
    if not (0 <= x < cols and 0 <= y < rows):
        raise ScenarioError(
            f"robot {robot.name!r} starts at {list(robot.start)}, outside the {cols}x{rows} map;"
            " give a start with 0 <= x < columns and 0 <= y < rows (x = column, y = row)."
        )
    if occupied[int(y), int(x)]:
        raise overlapping(robot)


def overlapping(robot: RobotSpec) -> ScenarioError:
    """The error of a robot whose start is inside or overlapping a wall."""
    return ScenarioError(
        f"robot {robot.name!r} starts at {list(robot.start)} inside or overlapping a wall"
        f" (radius {robot.radius}); move its start into free space at least its radius"
        " away from any obstacle."
    )


def check_base(occupied: BoolGrid, base: BaseStationSpec) -> None:
    """The base station must stand inside the map, on a free cell."""
    where, fix = "base_station.position", "move the base station into free space"
    check_free_cell(occupied, where, base.position, fix)


def check_free_cell(occupied: BoolGrid, where: str, point: tuple[float, float], fix: str) -> None:
    """The point ``where`` names must lie inside the map, on a free cell (``fix``: what
    the message tells the user to do about a wall)."""
    rows, cols = occupied.shape
    x, y = point
    if not (0 <= x < cols and 0 <= y < rows):
        raise ScenarioError(
            f"{where} {[x, y]} is outside the {cols}x{rows} map;"
            " give 0 <= x < columns and 0 <= y < rows."
        )
    if occupied[int(y), int(x)]:
        raise ScenarioError(
            f"{where} {[x, y]} is inside a wall (cell column {int(x)}, row"
            f" {int(y)} is an obstacle); {fix}."
        )


MAX_PAIRS_SHOWN = 5  # overlapping start pairs named in the message


def check_apart(robots: list[RobotSpec]) -> None:
    """With ``simulation.robots_block``, no two robots' bodies may overlap at their starts."""
    starts = np.array([r.start for r in robots], dtype=np.float64).reshape(-1, 2)
    radii = np.array([r.radius for r in robots], dtype=np.float64)
    pairs: list[tuple[int, int]] = []
    for i in range(len(robots) - 1):
        gaps = np.hypot(*(starts[i + 1 :] - starts[i]).T) - radii[i + 1 :] - radii[i]
        pairs += [(i, i + 1 + int(j)) for j in np.flatnonzero(gaps < 0)]
    if pairs:
        raise ScenarioError(
            f"robots {pair_names(robots, pairs)} start with overlapping bodies, which"
            " simulation.robots_block: true does not allow; place every start at least the"
            " sum of the two radii from every other."
        )


def pair_names(robots: list[RobotSpec], pairs: list[tuple[int, int]]) -> str:
    """``'A' and 'B', 'A' and 'C' (and 7 more pairs)``: the first few pairs by name."""
    shown = [f"{robots[i].name!r} and {robots[j].name!r}" for i, j in pairs[:MAX_PAIRS_SHOWN]]
    extra = len(pairs) - len(shown)
    return ", ".join(shown) + (f" (and {extra} more pairs)" if extra else "")


def check_event_boxes(scenario: Scenario, shape: tuple[int, int]) -> None:
    """Every map window an event names must lie inside the map."""
    rows, cols = shape
    for i, event in enumerate(scenario.events):
        for where, (row0, row1, col0, col1) in event.boxes():
            if not (0 <= row0 < row1 <= rows and 0 <= col0 < col1 <= cols):
                raise ScenarioError(
                    f"events[{i}].{where}: the window x {col0}..{col1}, y {row0}..{row1} is not"
                    f" inside the {cols}x{rows} map; give 0 <= x0 < x1 <= {cols} and"
                    f" 0 <= y0 < y1 <= {rows}."
                )


def check_door_names(scenario: Scenario) -> None:
    """Every door an event names must be in the scenario's doors list."""
    doors = {d.name for d in scenario.doors}
    for i, params in enumerate(scenario.events):
        for where, door in params.doors():
            if door not in doors:
                known = ", ".join(sorted(doors)) or "none: add a 'doors' list"
                raise ScenarioError(
                    f"events[{i}].{where}: there is no door called {door!r} (doors: {known})."
                )
