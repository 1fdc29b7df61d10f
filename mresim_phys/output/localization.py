"""summary.json's ``localization`` object (output): pose errors over the run and map consistency.

A run whose robots have localisation (``localization/feature.py``) gets, besides its
per-step columns (``pose_error``, ``heading_error``, ``pose_error_mean``,
``pose_error_max``):

* per robot: its position error at the end, its largest and its mean over the steps, its
  heading error at the end (degrees), the corrections it fused per kind, and its map's
  consistency with the truth at the end;
* the team: the mean position error at the end, the largest of any robot at any step and
  the mean over robots and steps;
* the base station's map consistency at the end.

Map consistency counts two kinds of wrong cells: ``false_free`` (believed FREE, truly an
obstacle: a ghost opening, smeared free space through a wall) and ``false_occupied``
(believed OCCUPIED, truly free and reachable: a ghost wall), each as a fraction of the
reachable free area (the cells the team's bodies can reach), so a run without drift has
``false_free`` 0 and ``false_occupied`` only where a bump or a wall face was marked a cell
off.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from mresim_phys.localization.feature import LOCALIZATION, PoseBelief
from mresim_phys.metrics import StepRecord
from mresim_phys.snapshot import Snapshot
from mresim_phys.types import FREE, OCCUPIED, BeliefGrid, BoolGrid

if TYPE_CHECKING:
    from mresim_phys.sim import Simulation


@dataclass
class PoseRecorder:
    """Each robot's position error step by step, as the records give it (a recorder)."""

    errors: dict[str, list[float]] = field(default_factory=dict)

    def on_step(self, record: StepRecord, snapshot: Callable[[], Snapshot]) -> None:
        """Note each robot's error at this step (robots without localisation: none)."""
        self.note(record)

    def note(self, record: StepRecord) -> None:
        """Note each robot's error at the step of ``record`` (a live run's or a replay's)."""
        for robot in record.robots:
            belief = LOCALIZATION.of(robot)
            if belief is not None and robot.state != "failed":
                self.errors.setdefault(robot.name, []).append(belief.error)

    def close(self) -> None:
        """Nothing to flush."""

    def discard(self) -> None:
        """Nothing to release."""


def consistency(belief: BeliefGrid, truth: BoolGrid, reachable: BoolGrid) -> dict[str, float]:
    """``false_free`` and ``false_occupied`` of ``belief`` against ``truth`` (module
    docstring), as fractions of the ``reachable`` area."""
    area = max(int(np.count_nonzero(reachable)), 1)
    false_free = int(np.count_nonzero((belief == FREE) & truth))
    false_occupied = int(np.count_nonzero((belief == OCCUPIED) & reachable & ~truth))
    return {"false_free": false_free / area, "false_occupied": false_occupied / area}


def localization_summary(sim: Simulation, poses: PoseRecorder | None) -> dict[str, Any]:
    """summary.json's ``localization`` object (module docstring); {} for a run without
    localisation."""
    beliefs = {r.name: LOCALIZATION.value_in(r.features) for r in sim.robots}
    maps = {r.name: r.belief for r in sim.robots}
    truth, reachable = sim.world.occupied, sim.setup.reachable.mask
    return localization_object(beliefs, maps, sim.base.belief, (truth, reachable), poses)


def replayed_localization(
    snap: Snapshot, reachable: BoolGrid, poses: PoseRecorder | None
) -> dict[str, Any]:
    """The ``localization`` object recomputed from a replay's last step (``reachable``: the
    free cells 4-connected to the starts, as the replay keeps them)."""
    beliefs = {r.name: LOCALIZATION.of(r) for r in snap.robots}
    maps = {r.name: r.belief for r in snap.robots}
    return localization_object(beliefs, maps, snap.base.belief, (snap.truth, reachable), poses)


def localization_object(
    beliefs: dict[str, PoseBelief | None],
    maps: dict[str, BeliefGrid],
    base: BeliefGrid,
    world: tuple[BoolGrid, BoolGrid],
    poses: PoseRecorder | None,
) -> dict[str, Any]:
    """The object from each robot's last belief (None: no localisation) and map, the
    base's map, the truth and its reachable cells, and the errors step by step."""
    if poses is None or not any(b is not None for b in beliefs.values()):
        return {}
    truth, reachable = world
    robots = {
        name: _robot(belief, poses.errors.get(name, []), consistency(maps[name], truth, reachable))
        for name, belief in beliefs.items()
        if belief is not None
    }
    every = [e for errors in poses.errors.values() for e in errors]
    finals = [v["final_error"] for v in robots.values()]
    return {
        "localization": {
            "robots": robots,
            "team": {
                "final_mean_error": float(np.mean(finals)),
                "max_error": max(every, default=0.0),
                "mean_error": float(np.mean(every)) if every else 0.0,
            },
            "base": consistency(base, truth, reachable),
        }
    }


def _robot(belief: PoseBelief, errors: list[float], maps: dict[str, float]) -> dict[str, Any]:
    """One robot's entry."""
    return {
        "final_error": belief.error,
        "max_error": max(errors, default=belief.error),
        "mean_error": float(np.mean(errors)) if errors else belief.error,
        "final_heading_error_deg": float(np.degrees(belief.heading_error)),
        "corrections": belief.corrections(),
        **maps,
    }
