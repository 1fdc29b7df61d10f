"""``mresim validate`` (output edge): a scenario checked without the simulator.

The scenario file is read and validated (schema, plugins and their parameters, files), its
map read, and what the map's grid alone can check is checked (``scenario/on_map.py``):
pydantic, PyYAML, numpy and Pillow, never numba, pymunk or OpenCV, in well under 1.5 s.
``--explorable`` builds the run's world as ``mresim run`` does (each start's clearance from
the exact walls, doors, terrain, the prior map) and reports where the team can go and what
it can see (``commands.explorable_command``).
"""

from __future__ import annotations

import argparse
from collections.abc import Callable

import numpy as np

from mresim_phys.errors import ScenarioError
from mresim_phys.plugin import named_object
from mresim_phys.scenario.load import load_scenario
from mresim_phys.scenario.on_map import check_on_map
from mresim_phys.scenario.schema import Scenario

EXPLORABLE = "mresim_phys.commands:explorable_command"  # the simulator: only when asked
WORLD_KEYS = ("obstacles", "doors", "random_debris", "terrain", "prior")  # placed on the world


def validate_command(args: argparse.Namespace) -> int:
    """Check the scenario at ``args.scenario`` and print one ``ok`` line (or, with
    ``--explorable``, the explorable report)."""
    if args.explorable:
        explorable: Callable[[argparse.Namespace], int] = named_object(EXPLORABLE)
        return explorable(args)
    scenario = load_scenario(args.scenario)
    try:
        truth = check_on_map(scenario)
    except ScenarioError as exc:
        raise ScenarioError(f"{args.scenario}: {exc}") from None
    rows, cols = truth.occupied.shape
    free = int(np.count_nonzero(~truth.occupied))
    print(
        f"{ok_line(scenario, str(args.scenario))}\n  map {cols}x{rows} cells ({free:,} free):"
        " starts, base station, event windows and doors checked on its grid\n  left to"
        " --explorable (or mresim run), which builds the world: "
        + ", ".join(left_to_the_world(scenario))
    )
    return 0


def left_to_the_world(scenario: Scenario) -> list[str]:
    """What only the built world checks, among what ``scenario`` has."""
    parts = ["each start's clearance from the exact walls"]
    parts += [key for key in WORLD_KEYS if getattr(scenario, key)]
    if scenario.faults is not None and scenario.faults.hazards:
        parts.append("faults.hazards regions")
    if any("world" in event.changes for event in scenario.events):
        parts.append("the regions of events that change the world")
    return parts


def ok_line(scenario: Scenario, label: str) -> str:
    """``label: ok (N robots, map PATH)``."""
    return f"{label}: ok ({len(scenario.robots)} robots, map {scenario.map.source[1]})"
