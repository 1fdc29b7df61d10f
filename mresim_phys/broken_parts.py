"""Broken parts (shared; phase 1, faults): a robot's failures in force, a per-robot feature.

A robot's parts (``drive``, ``sensor``, ``radio``, the whole ``robot``) fail and are
repaired by fault events and clocks (``faults/``), and a degradation scales its speed and
laser range. What is in force is the state of the feature :data:`PARTS` in
``Robot.features["parts"]`` (``features.py``): :class:`Parts`, the failures in force per
part (failures of one part add up: it works again once each has been repaired) and the
(speed, range) factors of the degradations in force. A robot nothing has failed has no
entry, so the per-scan question "what is broken?" is one dict lookup.

Its value, what the robot's strategy sees, is the set of parts that do not work
(``degraded`` while a degradation is in force). Snapshots record it while it is not empty
(``AgentSnapshot.features["parts"]``; the run log stores it as the sorted list ``parts``,
logs of version 6 or older as ``broken``), frames label the robot with it (``B [radio]``,
a ring around the robot), the viewer's hover row lists it, and teammates hear it in the
robot's record (``TeammateInfo.broken``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

from mresim_phys.features import HasFeatures, NameSetFeature

FailingPart = Literal["robot", "drive", "sensor", "radio", "degraded", "localization"]
Factors = tuple[float, float]  # (speed factor, sensor range factor) of a degraded robot
NOTHING_BROKEN: frozenset[str] = frozenset()  # the broken parts of a robot nothing has failed


@dataclass(frozen=True)
class Parts:
    """The failures in force: per part how many, and the degradations' factors."""

    holds: Mapping[str, int] = field(default_factory=dict)
    degradations: tuple[Factors, ...] = ()

    @property
    def broken(self) -> frozenset[str]:
        """The parts that do not work (``degraded`` while a degradation is in force)."""
        parts = {p for p, n in self.holds.items() if n > 0 and p != "robot"}
        return frozenset(parts | ({"degraded"} if self.degradations else set()))


class BrokenParts(NameSetFeature[Parts]):
    """A robot's failures in force (module docstring)."""

    key = "parts"
    omit_empty = True  # a robot whose parts were all repaired records nothing

    def value(self, state: Parts) -> frozenset[str]:
        """The parts that do not work."""
        return state.broken

    def label(self, value: frozenset[str]) -> str:
        """`` [drive,radio]``."""
        return f" [{','.join(sorted(value))}]"


PARTS = BrokenParts()


def broken_in(states: Mapping[str, Any]) -> frozenset[str]:
    """The parts that do not work of a robot with feature ``states`` (``Robot.features``)."""
    parts: Parts | None = states.get(PARTS.key)
    return NOTHING_BROKEN if parts is None else parts.broken


def broken_of(holder: HasFeatures) -> frozenset[str]:
    """The parts that do not work of a robot's snapshot, record or view (the feature's
    value; none recorded: nothing is broken)."""
    return PARTS.of(holder) or NOTHING_BROKEN


def fail_part(states: dict[str, Any], part: FailingPart, factors: Factors = (1.0, 1.0)) -> None:
    """Put one failure of ``part`` in force (``degraded``: with ``factors``)."""
    parts: Parts = states.get(PARTS.key) or Parts()
    if part == "degraded":
        states[PARTS.key] = Parts(parts.holds, (*parts.degradations, factors))
    else:
        states[PARTS.key] = Parts(
            {**parts.holds, part: parts.holds.get(part, 0) + 1}, parts.degradations
        )


def repair_part(states: dict[str, Any], part: FailingPart, factors: Factors = (1.0, 1.0)) -> int:
    """Undo one failure of ``part`` (a degradation with ``factors``, if one is in force);
    returns the failures of ``part`` left in force."""
    parts: Parts = states.get(PARTS.key) or Parts()
    if part == "degraded":
        kept = list(parts.degradations)
        if factors in kept:
            kept.remove(factors)
        states[PARTS.key] = Parts(parts.holds, tuple(kept))
        return len(kept)
    left = max(parts.holds.get(part, 0) - 1, 0)
    states[PARTS.key] = Parts({**parts.holds, part: left}, parts.degradations)
    return left


def speed_factor(states: Mapping[str, Any]) -> float:
    """The product of the speed factors of the degradations in force (1: none)."""
    return _factor(states, 0)


def range_factor(states: Mapping[str, Any]) -> float:
    """The product of the sensor range factors of the degradations in force (1: none)."""
    return _factor(states, 1)


def _factor(states: Mapping[str, Any], which: int) -> float:
    """The product of factor ``which`` (0: speed, 1: range) of the degradations in force."""
    parts: Parts | None = states.get(PARTS.key)
    return 1.0 if parts is None else math.prod(f[which] for f in parts.degradations)
