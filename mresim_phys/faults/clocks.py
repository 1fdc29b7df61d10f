"""Fault models (phase 0, events): every robot's failure clocks, drawn from named streams.

Common random numbers: each random failure law ``k`` draws a robot's times between
failures from the stream ``fault/<k>`` of the seed, keyed by the robot's name, and
each hazard zone ``k`` draws a robot's exposure budget (how many steps inside it
survives) once at the start from the stream ``hazard/<k>``. Nothing the robot or its
strategy does moves a draw: the same seed gives the same failure steps for the same
exposure, whatever the strategy, the team's order or its other members.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mresim_phys.faults.spec import RandomFaultSpec

NEVER = 2**62  # a step no run reaches


def gap(spec: RandomFaultSpec, rng: np.random.Generator) -> int:
    """Steps from a clock's start (or a repair) to its next failure (at least 1)."""
    if spec.mtbf is not None:
        steps = float(rng.exponential(spec.mtbf))
    elif spec.shape is not None and spec.scale is not None:
        steps = spec.scale * float(rng.weibull(spec.shape))
    else:
        assert spec.probability is not None
        if spec.probability <= 0:
            return NEVER
        return min(int(rng.geometric(spec.probability)), NEVER)
    return max(1, min(math.ceil(steps), NEVER))


def exposure_budget(probability: float, rng: np.random.Generator) -> int:
    """Steps inside a hazard zone a robot survives before the one that fails it
    (geometric: the same law as a failure with ``probability`` at each step inside)."""
    if probability <= 0:
        return NEVER
    return min(int(rng.geometric(probability)), NEVER)


@dataclass
class FailureClock:
    """One robot's failures under one random law: the next failure and repair steps."""

    robot: str
    spec: RandomFaultSpec
    rng: np.random.Generator
    next_fail: int = NEVER
    next_repair: int = NEVER
    failures: int = 0

    def __post_init__(self) -> None:
        self.next_fail = self._from(self.spec.after)

    def _from(self, start: int) -> int:
        """The failure step a gap drawn now puts after ``start`` (NEVER past ``until``)."""
        step = start + gap(self.spec, self.rng)
        return NEVER if self.spec.until is not None and step > self.spec.until else step

    def due(self, step: int) -> str | None:
        """``fail`` or ``repair`` if this clock acts at ``step`` (and moves on), else None."""
        if step == self.next_repair:
            self.next_repair = NEVER
            self.next_fail = self._next_after(step)
            return "repair"
        if step != self.next_fail:
            return None
        self.failures += 1
        recover = self.spec.recover_after
        if self.spec.mode == "jump":  # a localisation jump is over at once: draw the next
            self.next_fail = self._next_after(step)
        elif recover is None:
            self.next_fail = NEVER  # broken for good: this clock is done
        else:
            self.next_repair, self.next_fail = step + recover, NEVER
        return "fail"

    def _next_after(self, step: int) -> int:
        """After a repair at ``step``: the next failure, unless the limit is reached."""
        limit = self.spec.max_failures
        return NEVER if limit is not None and self.failures >= limit else self._from(step)
