"""Benchmark of the robustness metrics: what watching for failures costs a step.

The library team (scenario 11: 8 robots, speed 10, laser 200) with three failures (B at
step 40, F's radio at step 60, D at step 80) and the robustness columns on
(``simulation.paired``), run for ``--steps`` steps:

1. the time inside the robustness code (``FailureWatch.update``: noticing failures, the
   knowledge lost at each, following recoveries; ``Curves.update``) as a share of the
   step, per step: the median and the mean over the run (the failure steps carry a full
   pass over the failed robot's map);
2. whole runs with the metrics on and off (their update methods replaced by no-ops),
   interleaved on / off in one process: median ms per step of each run, then the median
   over rounds of each and their ratio (the issue's bar: the metrics cost <= 5 %).

Run from the repository root: ``python benchmarks/bench_robustness.py [--rounds 5]``.
"""

from __future__ import annotations

import argparse
import statistics
from pathlib import Path
from time import perf_counter
from typing import Any

from mresim_phys.sim import Simulation

ROOT = Path(__file__).resolve().parent.parent
SCENARIO = ROOT / "scenarios" / "11_library_8_robots.yaml"
FAILURES = [
    {"step": 40, "fail": "B"},
    {"step": 60, "fail": "F", "part": "radio"},
    {"step": 80, "fail": "D"},
]


def build(steps: int) -> Simulation:
    """The library team with its failures, stopped by the step cap only."""
    overrides: dict[str, Any] = {
        "steps": steps,
        "events": FAILURES,
        "stop": {"known_at_base": None},
    }
    return Simulation.from_yaml(SCENARIO, **overrides, **{"simulation.paired": True})


class Timed:
    """Wraps a bound method, adding the seconds it takes to ``spent``."""

    def __init__(self, method: Any) -> None:
        self.method, self.spent = method, 0.0

    def __call__(self, *args: Any) -> Any:
        started = perf_counter()
        try:
            return self.method(*args)
        finally:
            self.spent += perf_counter() - started


def metric_share(steps: int) -> tuple[float, float, float]:
    """(median, mean, max) share of a step spent in the robustness code."""
    sim = build(steps)
    watch, curves = Timed(sim.failures.update), Timed(sim.curves.update)
    sim.failures.update, sim.curves.update = watch, curves  # type: ignore[method-assign]
    shares = []
    while not sim.finished():
        before = watch.spent + curves.spent
        started = perf_counter()
        sim.step()
        shares.append((watch.spent + curves.spent - before) / (perf_counter() - started))
    return statistics.median(shares), statistics.fmean(shares), max(shares)


def step_times(steps: int, on: bool) -> float:
    """Median ms per step of one run with the metrics on or off."""
    sim = build(steps)
    if not on:
        sim.failures.update = lambda *args: []  # type: ignore[method-assign]
        sim.curves.update = lambda record: None  # type: ignore[method-assign]
    times = []
    while not sim.finished():
        started = perf_counter()
        sim.step()
        times.append(perf_counter() - started)
    return statistics.median(times) * 1e3


def main() -> None:
    """Print the share of a step and the interleaved on / off medians."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--steps", type=int, default=150)
    args = parser.parse_args()
    step_times(20, True)  # warm up: compiled kernels load, caches fill
    median, mean, most = metric_share(args.steps)
    print(f"robustness code per step: median {median:.2%}, mean {mean:.2%}, max {most:.2%}")
    on: list[float] = []
    off: list[float] = []
    for k in range(args.rounds):
        order = (True, False) if k % 2 == 0 else (False, True)
        for flag in order:
            (on if flag else off).append(step_times(args.steps, flag))
    a, b = statistics.median(on), statistics.median(off)
    print(
        f"ms per step (median of {args.rounds} rounds): on {a:.2f}, off {b:.2f}, on/off {a / b:.3f}"
    )
    print(f"  on:  {', '.join(f'{t:.2f}' for t in on)}")
    print(f"  off: {', '.join(f'{t:.2f}' for t in off)}")


if __name__ == "__main__":
    main()
