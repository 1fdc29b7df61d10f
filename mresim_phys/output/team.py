"""summary.json's benchmark figures (output): success within a budget and the ``team`` object.

* ``success`` (with ``metrics.budget``): whether the run reached the budget's fraction
  (``explored`` or ``known_at_base``) within ``within`` steps, from the milestones; a run
  that stopped before it (or never got there) did not succeed.
* ``team`` (with ``metrics.team``): ``overlap``, ``workload_cv``, ``longest_path`` and each
  robot's ``discovered`` (first) cells at the end (``discovery_feature.py``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from mresim_phys.discovery_feature import DISCOVERY, overlap_of, workload_cv_of
from mresim_phys.scenario.run_specs import BudgetSpec
from mresim_phys.tracking import Milestones

if TYPE_CHECKING:
    from mresim_phys.sim import Simulation


def succeeded(budget: BudgetSpec, milestones: Milestones) -> bool:
    """Whether the budget's fraction was reached within its steps."""
    if budget.explored is not None:
        reached = milestones.explored.get(str(budget.explored))
    else:
        reached = milestones.known_at_base.get(str(budget.known_at_base))
    return reached is not None and reached <= budget.within


def team_summary(sim: Simulation) -> dict[str, Any]:
    """The run's ``success`` and ``team`` entries (module docstring); {} for neither."""
    spec = sim.scenario.metrics
    out: dict[str, Any] = {}
    if spec.budget is not None:
        out["success"] = succeeded(spec.budget, sim.milestones)
    if spec.team:
        values = {r.name: DISCOVERY.value_in(r.features) for r in sim.robots}
        found = [v for v in values.values() if v is not None]
        out["team"] = {
            "overlap": overlap_of(found),
            "workload_cv": workload_cv_of(found),
            "longest_path": max((r.distance for r in sim.robots), default=0.0),
            "discovered": {name: v.first for name, v in values.items() if v is not None},
        }
    return out
