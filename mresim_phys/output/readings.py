"""summary.json's ``readings`` object (output): beam-model lasers' readings and their maps.

A run whose robots have a beam model (``world/beam.py``, feature ``readings``) gets, per
robot, how its rays read over the run (hit, short, max, rand, dropped, and the returns its
speckle filter left out) and its map's consistency with the truth at the end
(``false_free``, ``false_occupied``: ``output/localization.consistency``); and the base
station's map consistency. ``mresim replay --metrics`` recomputes it from the log.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from mresim_phys.output.localization import consistency
from mresim_phys.readings_feature import READINGS, Readings
from mresim_phys.snapshot import Snapshot
from mresim_phys.types import BeliefGrid, BoolGrid

if TYPE_CHECKING:
    from mresim_phys.sim import Simulation


def readings_summary(sim: Simulation) -> dict[str, Any]:
    """summary.json's ``readings`` object (module docstring); {} without a beam model."""
    values = {r.name: READINGS.value_in(r.features) for r in sim.robots}
    maps = {r.name: r.belief for r in sim.robots}
    world = (sim.world.occupied, sim.setup.reachable.mask)
    return readings_object(values, maps, sim.base.belief, world)


def replayed_readings(snap: Snapshot, reachable: BoolGrid) -> dict[str, Any]:
    """The ``readings`` object recomputed from a replay's last step."""
    values = {r.name: READINGS.of(r) for r in snap.robots}
    maps = {r.name: r.belief for r in snap.robots}
    return readings_object(values, maps, snap.base.belief, (snap.truth, reachable))


def readings_object(
    values: dict[str, Readings | None],
    maps: dict[str, BeliefGrid],
    base: BeliefGrid,
    world: tuple[BoolGrid, BoolGrid],
) -> dict[str, Any]:
    """The object from each robot's readings (None: no beam model) and map, the base's
    map, the truth and its reachable cells."""
    if not any(v is not None for v in values.values()):
        return {}
    truth, reachable = world
    robots = {
        name: {**value.as_dict(), **consistency(maps[name], truth, reachable)}
        for name, value in values.items()
        if value is not None
    }
    return {"readings": {"robots": robots, "base": consistency(base, truth, reachable)}}
