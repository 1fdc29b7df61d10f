"""Robustness outputs (output edge): a run's robustness figures and its paired baseline.

:func:`run_robustness` adds to every ``summary.json`` the areas under the explored and
known-at-base curves (``metrics.normalised_area``), the fraction of robots alive at the
end, ``base_deficit_at_end`` (reachable free cells the base's map does not hold FREE at
the end) and the ``failures`` list (``knowledge.robustness``).

A paired run (``mresim run --paired`` or ``simulation.paired: true``) then runs the same
scenario and seed with every fault switched off (``scenario.faults.without_faults``) in
the same process and writes ``robustness.json``: the baseline's figures, the run's, their
differences (run minus baseline) and ratios (run / baseline). A threshold never reached
is censored: its difference and ratio are null (never a number made up from the step cap)
and ``never`` lists it. Areas are compared over the common horizon: the longer run's step count, the
shorter curve holding its last value (a run stopped by a rule keeps what it knew).
Formulas: docs/robustness.md.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from mresim_phys.errors import ScenarioError
from mresim_phys.metrics import normalised_area
from mresim_phys.output.files import write_json_atomic
from mresim_phys.scenario.faults import paired_problem, without_faults
from mresim_phys.tracking import Curves
from mresim_phys.types import FREE

if TYPE_CHECKING:
    from mresim_phys.output.signals import StopRequest
    from mresim_phys.sim import Simulation

ROBUSTNESS_FILE = "robustness.json"
COMPARED = ("explored", "known_at_base")
SIDES = ("run", "baseline")


def run_robustness(sim: Simulation) -> dict[str, Any]:
    """The robustness fields of ``sim``'s summary.json, at its last step."""
    coverage, robots = sim.coverage, sim.robots
    held = np.count_nonzero((sim.base.belief == FREE) & coverage.reachable)
    deficit = max(coverage.total - int(held), 0)
    return {
        "auc_explored": normalised_area(sim.curves.explored),
        "auc_known_at_base": normalised_area(sim.curves.known_at_base),
        "alive_fraction": sum(r.alive for r in robots) / len(robots),
        "base_deficit_at_end": deficit,
        "base_deficit_fraction_at_end": deficit / coverage.total if coverage.total else 0.0,
        "failures": sim.failures.summary(),
    }


def check_paired(sim: Simulation) -> None:
    """A paired run needs faults to switch off: ScenarioError otherwise."""
    problem = paired_problem(sim.scenario)
    if problem is not None:
        raise ScenarioError(problem)


def run_baseline(sim: Simulation, stop: StopRequest | None = None) -> Simulation | None:
    """``sim``'s scenario with every fault switched off, run to its end in this process
    (None if a stop signal came first)."""
    from mresim_phys.sim import Simulation

    baseline = Simulation(without_faults(sim.scenario))
    for _ in baseline.iterate():
        if stop is not None and stop.requested:
            return None
    return baseline


def figures(sim: Simulation) -> dict[str, Any]:
    """One side of the comparison: what robustness.json says of a run."""
    last = sim.record
    return {
        "steps": last.step,
        "stop_reason": sim.stop_reason(),
        "steps_to_explored": dict(sim.milestones.explored),
        "steps_to_known_at_base": dict(sim.milestones.known_at_base),
        "final_explored": last.explored,
        "final_known_at_base": last.known_at_base,
        **{k: v for k, v in run_robustness(sim).items() if k != "failures"},
        "failures": len(sim.failures.failures),
    }


def ratio(a: float, b: float) -> float | None:
    """``a / b``, None when ``b`` is 0."""
    return a / b if b else None


def compare(out: dict[str, Any], key: str, run: float, base: float) -> None:
    """Note ``run - base`` and ``run / base`` under ``key``."""
    out["difference"][key], out["ratio"][key] = run - base, ratio(run, base)


def comparison(run: Simulation, base: Simulation) -> dict[str, Any]:
    """Differences (run - baseline) and ratios (run / baseline) of the headline figures."""
    horizon = max(run.record.step, base.record.step)
    out: dict[str, Any] = {"horizon": horizon, "difference": {}, "ratio": {}, "never": []}
    for name in COMPARED:
        key = f"steps_to_{name}_0.9"
        steps = [getattr(sim.milestones, name)["0.9"] for sim in (run, base)]
        sides = zip(SIDES, steps, strict=True)
        out["never"] += [f"{side}: {key}" for side, v in sides if v is None]
        if None in steps:  # censored: the run needed more than it had, by an unknown amount
            out["difference"][key] = out["ratio"][key] = None
        else:
            compare(out, key, *steps)
        areas = [normalised_area(curve(sim.curves, name), horizon) for sim in (run, base)]
        compare(out, f"auc_{name}", *areas)
        compare(out, f"final_{name}", getattr(run.record, name), getattr(base.record, name))
    return out


def curve(curves: Curves, name: str) -> list[float]:
    """One of the curves by name."""
    values: list[float] = getattr(curves, name)
    return values


def write_robustness(
    sim: Simulation, folder: Path, stop: StopRequest | None = None
) -> dict[str, Any] | None:
    """Run the baseline of a paired run and write ``robustness.json`` into ``folder``
    (nothing for an unpaired run; the baseline's stop reason alone if a signal stopped it)."""
    if not sim.scenario.simulation.paired:
        return None
    baseline = run_baseline(sim, stop)
    report: dict[str, Any] = {"name": sim.scenario.name, "seed": sim.scenario.seed}
    if baseline is None:
        report["baseline"] = {"stop_reason": "interrupted"}
    else:
        report |= {
            "run": figures(sim),
            "baseline": figures(baseline),
            **comparison(sim, baseline),
        }
    write_json_atomic(folder / ROBUSTNESS_FILE, report)
    return report
