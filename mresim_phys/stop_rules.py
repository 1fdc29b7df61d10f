"""Stop rules (phase 7, measure): why a run stops after a step.

``stop.explored`` and ``stop.known_at_base`` (a fraction reached), ``stop.all_done``
(every robot failed, or done and arrived), ``stop.stalled_for`` (no progress:
``tracking.StallWatch``) and the step cap, in that order.
"""

from __future__ import annotations

from collections.abc import Sequence

from mresim_phys.agents import Robot
from mresim_phys.build import RunRules
from mresim_phys.metrics import StepRecord
from mresim_phys.tracking import StallWatch


def stop_reason(
    rules: RunRules, record: StepRecord, robots: Sequence[Robot], stall: StallWatch
) -> str | None:
    """Why the run stops after ``record``'s step (``steps``, ``explored``,
    ``known_at_base``, ``all_done``, ``stalled``), or None."""
    t = record.step
    if rules.stop_explored is not None and record.explored >= rules.stop_explored:
        return "explored"
    known = record.known_at_base
    if rules.stop_known_at_base is not None and known >= rules.stop_known_at_base:
        return "known_at_base"
    if rules.stop_all_done and all_idle(robots):
        return "all_done"
    if t < rules.steps and stall.stalled(t):
        return "stalled"
    return "steps" if t >= rules.steps else None


def all_idle(robots: Sequence[Robot]) -> bool:
    """Every robot has failed, or is done and has arrived where it was going."""
    return all(not r.alive or (r.done and len(r.path) == 0) for r in robots)
