"""Explorable-area report (output edge): what ``mresim validate`` says about where a team can go.

For each robot size (radius and laser range) of the team: the share of the map's free
cells those robots' bodies can reach (cell centres, ``world.explorable``) and see, then
the team's explorable share. Warnings (the scenario still validates) name a robot that

* can reach less than :data:`POCKET_SHARE` of the free cells: most of the map is out of
  its body's reach (narrow doors, a start in a corner of rubble), so its explored share
  of the map will stay low whatever its strategy does;
* starts in a pocket: its reachable positions meet no other robot's, or lie in a free
  region apart from the base station's (it could never bring its map home).
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from scipy import ndimage

from mresim_phys.types import BoolGrid
from mresim_phys.validation import ok_line
from mresim_phys.world.explorable import Explorable
from mresim_phys.world.maps import FOUR_CONNECTED, free_components_mask

if TYPE_CHECKING:
    from mresim_phys.sim import Simulation

POCKET_SHARE = 0.25  # a robot reaching less of the free cells than this is warned about


@dataclass(frozen=True)
class Region:
    """Where one robot's body can go: its reachable positions."""

    name: str
    radius: float
    cells: BoolGrid

    @property
    def size(self) -> int:
        """Its reachable positions."""
        return int(np.count_nonzero(self.cells))


def regions(explorable: Explorable, names: Sequence[str]) -> list[Region]:
    """Each robot's reachable positions (the region of its positions holding its seeds)."""
    labels = {
        radius: ndimage.label(places, structure=FOUR_CONNECTED)[0]
        for radius, places in explorable.places.items()
    }
    out = []
    for name, robot in zip(names, explorable.robots, strict=True):
        grid = labels[robot.radius]
        ids = [int(grid[r, c]) for r, c in robot.seeds or () if grid[r, c] > 0]
        out.append(Region(name, robot.radius, np.isin(grid, ids)))
    return out


def percent(part: int, whole: int) -> str:
    """``part`` of ``whole`` as a percentage with one decimal.

    >>> percent(1, 3)
    '33.3 %'
    """
    return f"{100 * part / whole if whole else 100.0:.1f} %"


def size_lines(explorable: Explorable, names: Sequence[str], free: int) -> list[str]:
    """One line per robot size: who, the share of free cells reached and seen."""
    lines = []
    for group in explorable.groups:
        members = [
            n
            for n, r in zip(names, explorable.robots, strict=True)
            if (r.radius, r.sensor_range) == (group.radius, group.sensor_range)
        ]
        reach, seen = int(np.count_nonzero(group.reach)), int(np.count_nonzero(group.seen))
        lines.append(
            f"robots of radius {group.radius:g} and laser range {group.sensor_range:g}"
            f" ({', '.join(members)}): reach {percent(reach, free)} of the free cells,"
            f" see {percent(seen, free)}"
        )
    return lines


def print_team_report(sim: Simulation, label: str) -> None:
    """``mresim validate``'s output: ``label: ok``, the scenario in a few words and
    :func:`team_report`'s lines on stdout, its warnings on stderr."""
    lines, warnings = team_report(sim)
    print("\n  ".join([ok_line(sim.scenario, label), *lines]))
    for warning in warnings:
        print(f"mresim: warning: {warning}", file=sys.stderr)


def team_report(sim: Simulation) -> tuple[list[str], list[str]]:
    """:func:`report` on the scenario's map as loaded (before any event), for ``sim``'s
    team from where it starts."""
    setup, scenario = sim.setup, sim.scenario
    occupied = setup.truth.occupied
    explorable = Explorable(occupied, setup.explorable.robots)
    connected = int(np.count_nonzero(free_components_mask(occupied, setup.starts)))
    base = scenario.base_station.position
    names = [r.name for r in scenario.robots]
    return report(explorable, occupied, names, (base[0], base[1]), connected)


def report(
    explorable: Explorable,
    occupied: BoolGrid,
    names: Sequence[str],
    base: tuple[float, float],
    connected: int,
) -> tuple[list[str], list[str]]:
    """(lines, warnings) about ``explorable`` on ``occupied`` for robots ``names`` (in
    order) with the base station at ``base``; ``connected``: the free cells 4-connected to
    the starts (the definition before the explorable area)."""
    free = int(np.count_nonzero(~occupied))
    lines = [f"free cells: {free:,}; 4-connected to the starts: {percent(connected, free)}"]
    lines += size_lines(explorable, names, free)
    team = int(np.count_nonzero(explorable.mask))
    lines.append(f"team: explorable {percent(team, free)} of the free cells ({team:,} cells)")
    return lines, warnings(regions(explorable, names), occupied, base, free)


def warnings(
    found: list[Region], occupied: BoolGrid, base: tuple[float, float], free: int
) -> list[str]:
    """The warnings about robots that reach little or start in a pocket."""
    areas = ndimage.label(~occupied, structure=FOUR_CONNECTED)[0]
    base_area = areas[int(base[1]), int(base[0])]
    out = []
    for region in found:
        name = f"robot {region.name!r} (radius {region.radius:g})"
        if region.size < POCKET_SHARE * free:
            out.append(
                f"{name} can reach only {percent(region.size, free)} of the free cells (warned"
                f" below {POCKET_SHARE:.0%}): narrow passages or its start keep its body out"
                " of the rest of the map"
            )
        others = [o for o in found if o is not region]
        if others and not any((o.cells & region.cells).any() for o in others):
            out.append(f"{name} starts in a pocket: no other robot can reach where it can go")
        if region.size and not (areas[region.cells] == base_area).any():
            out.append(
                f"{name} starts in a pocket: no free path leads from where it can go to the"
                " base station"
            )
    return out
