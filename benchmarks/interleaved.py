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
    medians: dict[str, list[float]] = {name: [] for name in configurations}
    for _ in range(rounds):
        sims = {name: Simulation(validate_scenario(d)) for name, d in configurations.items()}
        times: dict[str, list[float]] = {name: [] for name in configurations}
        for step in range(warmup + steps):
            for name, sim in sims.items():
                started = perf_counter()
                sim.step()
                if step >= warmup:
                    times[name].append(perf_counter() - started)
        for name in configurations:
            medians[name].append(1e3 * statistics.median(times[name]))
    return medians
