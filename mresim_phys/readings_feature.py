"""A laser's readings (phase 2, a per-robot feature): how a beam-model laser read its rays.

Every robot whose ``sensor`` has a ``beam`` model (``world/beam.py``) gets the feature
``readings``: how many of its rays so far read a hit, a short return, no return (max), a
random return, or were lost, counted as its scans are read (``sensing_phase.Senses``). It
is logged (``[hit, short, max, rand, dropped, filtered]`` in each robot's line of the run log), so a
replay has it back; frames add the share of rays that did not read the true distance beside
the robot's name (robot layer ``readings``: ``A z12%``), the viewer's hover row shows the
counts (with the returns its speckle filter left out), and summary.json's ``readings``
object (``output/readings.py``) gives them per robot with each map's consistency with the
truth at the end.

Column (``metrics.columns: [noisy_readings]``, written for runs with a beam model):
``noisy_readings``, the share of the team's rays so far that read anything but a hit.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from mresim_phys.columns import column
from mresim_phys.features import RobotFeature
from mresim_phys.memory import sparse_zeros
from mresim_phys.world.beam import KINDS

if TYPE_CHECKING:
    from mresim_phys.metrics import StepRecord


@dataclass(frozen=True)
class Readings:
    """A robot's rays so far, by how they read."""

    hit: int = 0
    short: int = 0
    max: int = 0
    rand: int = 0
    dropped: int = 0
    filtered: int = 0  # returns the robot's speckle filter left out (counted in a kind too)

    @property
    def total(self) -> int:
        """Every ray cast."""
        return self.hit + self.short + self.max + self.rand + self.dropped

    @property
    def noisy(self) -> int:
        """The rays that did not read a hit (short, max, random or lost)."""
        return self.total - self.hit

    def as_dict(self) -> dict[str, int]:
        """The counts, named."""
        return {kind: int(getattr(self, kind)) for kind in KINDS}


@dataclass
class ReadingCounts:
    """The state the sensing phase adds to: counts per kind (``world.beam.KINDS``) and the
    robot's evidence per cell (``knowledge/evidence.py``)."""

    evidence: np.ndarray
    counts: np.ndarray = field(default_factory=lambda: np.zeros(len(KINDS), dtype=np.int64))

    @classmethod
    def on(cls, shape: tuple[int, int]) -> ReadingCounts:
        """No readings yet, no evidence on a map of ``shape``."""
        return cls(sparse_zeros(shape, np.int8))


class ReadingsFeature(RobotFeature[ReadingCounts, Readings]):
    """A beam-model laser's readings (module docstring)."""

    key = "readings"
    layer = "readings"

    def value(self, state: ReadingCounts) -> Readings:
        """The counts so far."""
        return Readings(*(int(v) for v in state.counts))

    def encode(self, value: Readings) -> Any:
        """``[hit, short, max, rand, dropped, filtered]``."""
        return [value.hit, value.short, value.max, value.rand, value.dropped, value.filtered]

    def decode(self, raw: Any) -> Readings:
        """The logged list read back."""
        return Readings(*(int(v) for v in raw))

    def label(self, value: Readings) -> str:
        """The share of rays that read anything but a hit: `` z12%``."""
        return f" z{value.noisy / value.total:.0%}" if value.total else ""

    def hover(self, value: Readings) -> Any:
        """The counts, named."""
        return value.as_dict()


READINGS = ReadingsFeature()


def beam_state(features: dict[str, object]) -> ReadingCounts | None:
    """The counts and evidence a robot's scans add to (None: its laser has no beam model)."""
    return READINGS.state_of(features)


@column("noisy_readings", optional=True)
def noisy_readings(r: StepRecord) -> float | None:
    """Share of the team's rays so far that read anything but a hit (beam-model lasers)."""
    readings = [v for v in (READINGS.of(robot) for robot in r.robots) if v is not None]
    if not readings:
        return None
    total = sum(v.total for v in readings)
    return sum(v.noisy for v in readings) / total if total else 0.0
