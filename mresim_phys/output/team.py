"""summary.json's benchmark figures (output): success within a budget and the ``team`` object.

* ``success`` (with ``metrics.budget``): whether the run reached the budget's fraction
  (``explored`` or ``known_at_base``) within ``within`` steps, from the milestones; a run
  that stopped before it (or never got there) did not succeed.
* ``team`` (with ``metrics.team``): ``overlap``, ``workload_cv``, ``longest_path`` and each
  robot's ``discovered`` (first) cells at the end (``discovery_feature.py``);
  ``mresim replay --metrics`` recomputes it from the log.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from mresim_phys.discovery_feature import DISCOVERY, Discovered, overlap_of, workload_cv_of
from mresim_phys.scenario.run_specs import BudgetSpec
from mresim_phys.snapshot import Snapshot
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
        out["team"] = team_object(values, [r.distance for r in sim.robots])
    return out


def replayed_team(snap: Snapshot) -> dict[str, Any]:
    """The ``team`` object recomputed from a replay's last step ({} without it)."""
    values = {r.name: DISCOVERY.of(r) for r in snap.robots}
    if not any(v is not None for v in values.values()):
        return {}
    return {"team": team_object(values, [r.distance for r in snap.robots])}


def team_object(values: dict[str, Discovered | None], distances: list[float]) -> dict[str, Any]:
    """The ``team`` object from each robot's discoveries and distance driven."""
    found = [v for v in values.values() if v is not None]
    return {
        "overlap": overlap_of(found),
        "workload_cv": workload_cv_of(found),
        "longest_path": max(distances, default=0.0),
        "discovered": {name: v.first for name, v in values.items() if v is not None},
    }
