"""Benchmark (output edge): ``mresim bench``, median milliseconds per step and where they go.

Builds a frontier-exploration team of 4, 8 and 16 robots (speed 3, radius 2,
range 100, disk comm 150) on an 800x600 floor plan, runs warm-up steps, then times
each step and reports the median and 90th percentile per step and the median
cost of each phase per step (sensing = ray casting, mapping = map updates,
planning = strategy decisions incl. frontiers and distance fields,
communication = links and merges, metrics; "motion" is the rest: path following
and swept-circle checks). Medians, not means: the machine may be shared.
"""

from __future__ import annotations

import statistics
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from time import perf_counter
from typing import Any

import numpy as np

from mresim_phys.errors import MresimError
from mresim_phys.scenario.load import validate_scenario
from mresim_phys.sim import PHASES, Simulation

PACKAGE_DATA = Path(__file__).resolve().parent.parent / "data"  # installed with the package
DEFAULT_MAP = PACKAGE_DATA / "office.png"
DEFAULT_BASE = (25.0, 300.0)
DEFAULT_START = (40.0, 300.0)


@dataclass(frozen=True)
class BenchResult:
    """Per-step timings of one team size (milliseconds)."""

    robots: int
    median_ms: float
    p90_ms: float
    phase_ms: dict[str, float]
    explored: float


def team_scenario(robots: int, map_path: Path, steps: int) -> dict[str, Any]:
    """A frontier team of ``robots`` starting in a row near the base."""
    x, y = DEFAULT_START
    starts = [[x + 8 * (i % 8), y + 8 * (i // 8) - 4] for i in range(robots)]
    return {
        "name": f"bench-{robots}",
        "seed": 1,
        "steps": steps,
        "stop": {"all_done": False, "stalled_for": None},
        "map": {"image": str(map_path)},
        "base_station": {"position": list(DEFAULT_BASE), "comm_range": 150},
        "team": {"speed": 3, "radius": 2, "sensor": {"range": 100}, "comm_range": 150},
        "robots": [{"name": f"R{i}", "start": s} for i, s in enumerate(starts)],
    }


def time_team(robots: int, map_path: Path, warmup: int, measured: int) -> BenchResult:
    """Run warm-up steps, then time ``measured`` steps of a team of ``robots``."""
    sim = Simulation(validate_scenario(team_scenario(robots, map_path, warmup + measured)))
    for _ in range(warmup):
        sim.step()
    totals: list[float] = []
    phases: dict[str, list[float]] = {name: [] for name in (*PHASES, "motion")}
    for _ in range(measured):
        before = dict(sim.phase_times)
        started = perf_counter()
        sim.step()
        total = perf_counter() - started
        totals.append(total)
        spent = {name: sim.phase_times[name] - before[name] for name in PHASES}
        for name, seconds in spent.items():
            phases[name].append(seconds)
        phases["motion"].append(max(total - sum(spent.values()), 0.0))
    return BenchResult(
        robots,
        1e3 * statistics.median(totals),
        1e3 * float(np.percentile(totals, 90)),
        {name: 1e3 * statistics.median(v) for name, v in phases.items()},
        sim.record.explored,
    )


def report(results: Sequence[BenchResult], map_path: Path) -> str:
    """The results as a text table."""
    names = [*PHASES, "motion"]
    head = f"{'robots':>6} {'median':>8} {'p90':>8} " + " ".join(f"{n:>13}" for n in names)
    lines = [f"mresim bench: frontier team on {map_path.name}, ms per step", head]
    for r in results:
        split = " ".join(f"{r.phase_ms[n]:13.2f}" for n in names)
        lines.append(f"{r.robots:>6} {r.median_ms:8.2f} {r.p90_ms:8.2f} {split}")
    lines.append("(phase columns are per-step medians; they need not add up to the median)")
    return "\n".join(lines)


def run_bench(
    robot_counts: Sequence[int], map_path: Path | None, warmup: int, measured: int
) -> str:
    """Time every team size and return the report."""
    path = map_path or DEFAULT_MAP
    if not path.is_file():
        raise MresimError(
            f"benchmark map {path} not found; give one with --map (an 800x600 floor plan whose"
            f" free space contains {list(DEFAULT_BASE)} and the row of starts from"
            f" {list(DEFAULT_START)})."
        )
    results = [time_team(n, path, warmup, measured) for n in robot_counts]
    return report(results, path)
