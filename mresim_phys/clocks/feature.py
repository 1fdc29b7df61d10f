"""A robot's clock (phase 1, decide; a per-robot feature): when it acts, decides and scans.

Every robot with a ``clock:`` block (``clocks/spec.py``) has the state :class:`Clock` in
``Robot.features["clock"]``, which ``clocks/gate.py`` reads and moves on each step: whether
the robot acts on this step (``act_every``, ``phase``), whether it may ask its strategy
(``decision_period``), the plan it has asked for and not yet follows (``compute_delay``),
and whether it scans on this step (``scan_period``).

The feature's value (:class:`ClockValue`) is what a strategy sees and a snapshot records:
the decisions its strategy made so far, the steps until its pending plan takes effect,
whether it acts on this step and the steps until its strategy may be asked again. It is
logged (``[decisions, wait, acting, ready_in]`` in each robot's line of the run log;
``wait`` is -1 with no plan pending), so a replay has it back; frames add the decisions
and the wait beside the robot's name (robot layer ``clock``: ``A c12~2``) and the viewer's
hover row shows all four. The run-health watch counts a robot its clock held still as
``waiting``, not idle or stuck (:meth:`ClockValue.holds`).

Column (``metrics.columns: [decisions]``, written for runs with a clock): ``decisions``,
the decisions the clocked robots' strategies made so far, summed.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from mresim_phys.clocks.spec import ClockSpec
from mresim_phys.columns import column
from mresim_phys.features import RobotFeature

if TYPE_CHECKING:
    from mresim_phys.metrics import StepRecord
    from mresim_phys.strategies import Decision


@dataclass(frozen=True)
class ClockValue:
    """What a robot's clock shows: decisions so far, steps until its pending plan takes
    effect (-1: none pending), whether it acts on this step, steps until its strategy may
    be asked again (0: now)."""

    decisions: int = 0
    wait: int = -1
    acting: bool = True
    ready_in: int = 0

    def holds(self, has_path: bool) -> bool:
        """Whether the clock, not the robot, kept it still this step: it did not act, or
        it had no path and waited for its plan or its decision period."""
        return not self.acting or (not has_path and (self.wait >= 0 or self.ready_in > 0))


@dataclass
class Clock:
    """A robot's clock as the run moves it (``clocks/gate.py``)."""

    spec: ClockSpec
    rng: np.random.Generator  # the robot's stream ``compute-delay`` (drawn when min < max)
    now: int = 0  # the step it was last ticked to
    origin: int = 0  # it acts on steps t with (t - origin) % act_every == 0
    acting: bool = True  # it acts on step ``now``
    scanning: bool = True  # it may scan on step ``now``
    last_scan: int | None = None
    last_decided: int | None = None  # the step its strategy was last asked
    decisions: int = 0
    pending: Decision | None = None  # a plan asked for and not yet followed
    decided_at: int = 0  # the step the pending plan was asked for
    due_at: int = 0  # the first step it may take effect on
    applied_at: int = -1  # the step the last plan that waited took effect
    held: Decision | None = None  # a caller's decision given on a step it does not act on
    odometer: float = 0.0  # the robot's distance when its pending plan was asked for
    was_alive: bool = True

    @classmethod
    def of(cls, spec: ClockSpec, rng: np.random.Generator) -> Clock:
        """A clock at step 0 (every robot scans where it starts)."""
        return cls(spec, rng, origin=spec.phase)

    def delay(self) -> int:
        """The steps a plan asked for now waits (drawn when the delay varies)."""
        low, high = self.spec.compute_delay.min, self.spec.compute_delay.max
        return low if low == high else int(self.rng.integers(low, high + 1))

    def ready_in(self, step: int) -> int:
        """Steps until its strategy may be asked again (0: now; a pending plan aside): its
        decision period after the last ask, and not on the step a plan that waited took
        effect."""
        last = self.last_decided
        period = 0 if last is None else last + self.spec.decision_period - step
        return max(0, period, self.applied_at + 1 - step)

    def scan(self) -> bool:
        """Whether the robot may scan on this step; a scan it takes is noted."""
        if self.scanning:
            self.last_scan = self.now
        return self.scanning


class ClockFeature(RobotFeature[Clock, ClockValue]):
    """A robot's clock (module docstring)."""

    key = "clock"
    layer = "clock"

    def value(self, state: Clock) -> ClockValue:
        """Decisions so far, the pending plan's wait, whether it acts now."""
        wait = max(state.due_at - state.now, 0) if state.pending is not None else -1
        return ClockValue(state.decisions, wait, state.acting, state.ready_in(state.now))

    def encode(self, value: ClockValue) -> Any:
        """``[decisions, wait, acting, ready_in]``."""
        return [value.decisions, value.wait, int(value.acting), value.ready_in]

    def decode(self, raw: Any) -> ClockValue:
        """The logged list read back."""
        return ClockValue(int(raw[0]), int(raw[1]), bool(raw[2]), int(raw[3]))

    def label(self, value: ClockValue) -> str:
        """`` c12`` (decisions so far), ``~2`` added while a plan waits 2 more steps."""
        return f" c{value.decisions}" + (f"~{value.wait}" if value.wait >= 0 else "")

    def hover(self, value: ClockValue) -> Any:
        """The four, named."""
        return {
            "decisions": value.decisions,
            "wait": value.wait,
            "acting": value.acting,
            "ready_in": value.ready_in,
        }


CLOCK = ClockFeature()


@column("decisions", optional=True)
def decisions(r: StepRecord) -> int | None:
    """Decisions the clocked robots' strategies made so far, summed (runs with a clock)."""
    values = [v for v in (CLOCK.of(robot) for robot in r.robots) if v is not None]
    return sum(v.decisions for v in values) if values else None
