"""Team size (sweeps, input): the ``robots.count`` axis and its placement rule.

A team of ``count`` robots keeps the scenario's robots in their order (the first
``count`` of them when the axis shrinks the team); each robot added is a plain team member
(the ``team`` fields, no fields of its own) called ``R<k>`` (the first free name), started
by ``mresim bench``'s rule (``output/bench.py``): rows of eight, ``SPACING`` cells apart,
beside the first robot's start, then the free spots nearest it, every start clear of the
walls by the largest body radius and ``SPACING`` cells from every other start. The rule
uses only the map, so every strategy and seed of a team size starts alike.
"""

from __future__ import annotations

import copy
from typing import Any

from mresim_phys.output.bench import SPACING, row_starts, spots_near
from mresim_phys.scenario.on_map import load_map
from mresim_phys.scenario.schema import Scenario
from mresim_phys.sweeps.study import StudyError
from mresim_phys.world.space import World

Point = tuple[float, float]


def resize_team(
    data: dict[str, Any], scenario: Scenario, count: Any, source: str
) -> dict[str, Any]:
    """``data`` with a team of ``count`` robots (``scenario``: ``data`` validated)."""
    if isinstance(count, bool) or not isinstance(count, int) or count < 1:
        raise StudyError(f"{source}: axis robots.count takes team sizes >= 1, got {count!r}.")
    result = copy.deepcopy(data)
    robots = list(result.get("robots") or [])
    if count <= len(robots):
        result["robots"] = robots[:count]
        return result
    taken = [point(r.start) for r in scenario.robots]
    starts = new_starts(scenario, taken, count - len(robots), source)
    names = free_names({r.name for r in scenario.robots}, len(starts))
    extra = [{"name": n, "start": list(p)} for n, p in zip(names, starts, strict=True)]
    result["robots"] = robots + extra
    return result


def point(xy: Any) -> Point:
    """A position as a pair of floats."""
    return float(xy[0]), float(xy[1])


def free_names(used: set[str], wanted: int) -> list[str]:
    """``wanted`` names ``R<k>`` not in ``used``, k counting from 1.

    >>> free_names({"R1", "A"}, 2)
    ['R2', 'R3']
    """
    names: list[str] = []
    k = 1
    while len(names) < wanted:
        if f"R{k}" not in used:
            names.append(f"R{k}")
        k += 1
    return names


def new_starts(scenario: Scenario, taken: list[Point], wanted: int, source: str) -> list[Point]:
    """``wanted`` starts by the bench rule beside the first robot, apart from ``taken``."""
    occupied = load_map(scenario.map).occupied
    rows, cols = (-(-n // SPACING) for n in occupied.shape)  # a start per SPACING square
    if len(taken) + wanted > rows * cols:
        raise StudyError(
            f"{source}: robots.count: the map has room for at most {rows * cols - len(taken)}"
            f" more robots {SPACING} cells apart, not {wanted}; sweep smaller teams."
        )
    world = World(occupied, [])
    radius = max([scenario.team.radius, *(r.radius for r in scenario.robots)])
    origin = taken[0] if taken else point(scenario.base_station.position)
    chosen: list[Point] = []

    def fits(p: Point) -> bool:
        far = all(abs(p[0] - q[0]) >= SPACING or abs(p[1] - q[1]) >= SPACING for q in taken)
        return far and not world.overlaps_wall(p, radius)

    for p in [*row_starts(len(taken) + wanted, origin), *spots_near(occupied, origin)]:
        if len(chosen) == wanted:
            break
        if fits(p):
            chosen.append(p)
            taken.append(p)
    if len(chosen) < wanted:
        raise StudyError(
            f"{source}: robots.count: the map has room for {len(chosen)} more robots"
            f" {SPACING} cells apart near {list(origin)}, not {wanted}; sweep smaller teams."
        )
    return chosen
