"""Interleaved rounds (benchmarks): several runs stepped in turn in one process.

Each round builds every configuration's simulation afresh and steps them one step each in
turn, so a busy spell of a shared machine hits all of them alike; a run's figure for the
round is its median ms per step after the warm-up.
"""

from __future__ import annotations

import statistics
from time import perf_counter
from typing import Any

from mresim_phys.scenario.load import validate_scenario
from mresim_phys.sim import Simulation


def step_medians(
    configurations: dict[str, dict[str, Any]], rounds: int, warmup: int, steps: int
) -> dict[str, list[float]]:
    """Per configuration (scenario data by name), its median ms per step in each round."""
    return phase_medians(configurations, rounds, warmup, steps)["step"]


def phase_medians(
    configurations: dict[str, dict[str, Any]],
    rounds: int,
    warmup: int,
    steps: int,
    phases: tuple[str, ...] = (),
) -> dict[str, dict[str, list[float]]]:
    """Per measure ("step" and each of ``phases``, as ``Simulation.phase_times`` names
    them) and configuration, its median ms per step in each round."""
    measures = ("step", *phases)
    medians = {m: {name: [] for name in configurations} for m in measures}
    for _ in range(rounds):
        sims = {name: Simulation(validate_scenario(d)) for name, d in configurations.items()}
        times: dict[str, dict[str, list[float]]] = {
            m: {name: [] for name in configurations} for m in measures
        }
        for step in range(warmup + steps):
            for name, sim in sims.items():
                before = {p: sim.phase_times.get(p, 0.0) for p in phases}
                started = perf_counter()
                sim.step()
                if step >= warmup:
                    times["step"][name].append(perf_counter() - started)
                    for p in phases:
                        times[p][name].append(sim.phase_times.get(p, 0.0) - before[p])
        for m in measures:
            for name in configurations:
                medians[m][name].append(1e3 * statistics.median(times[m][name]))
    return medians


def print_ratios(
    medians: dict[str, dict[str, list[float]]], base: str, other: str, bar: float
) -> None:
    """Each measure's median ms per step of ``base`` and ``other`` (over the rounds), the
    ratio (the bar shown on the whole step) and ``other``'s rounds."""
    for measure, by_run in medians.items():
        was, now = statistics.median(by_run[base]), statistics.median(by_run[other])
        rounds = " / ".join(f"{v:.2f}" for v in by_run[other])
        shown = f" (bar <= {bar})" if measure == "step" else ""
        print(
            f"  {measure:>8}: {base} {was:6.2f} ms, {other} {now:6.2f} ms,"
            f" x{now / was:.2f}{shown}; {other} rounds {rounds}"
        )
