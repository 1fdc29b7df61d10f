"""Benchmark of localisation (issue 31): what drift and its corrections cost a step.

The library team (8 robots, the original's settings, ``mresim bench --preset original``)
with every robot given a ``localization:`` block, against the same team that knows its
pose: median ms per step over the exploring phase, the runs stepped in turn in one process
(interleaved rounds), and each run's ratio to the exact one. The bars: drift alone <= 1.1,
scan matching every scan <= 1.6.

* ``zero alphas``: the machinery alone (the believed pose, the fold placed at it): the
  robots move exactly as the exact run's, so the ratio is the cost of the code path;
* ``drift``: the scenario library's alphas; the robots now bump and replan where the
  exact team does not, so the ratio holds what drift does to the exploration too;
* ``drift + base``, ``drift + teammate``, ``drift + scan matching``: each correction.

Run from the repository root: ``python benchmarks/bench_localization.py [--rounds 3]``.
"""

from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
from interleaved import step_medians

from mresim_phys.output.bench import PRESETS, team_scenario

PRESET = PRESETS["original"]
ALPHA = [0.0002, 0.000001, 0.0002, 0.000001]  # scenarios/27-29: the library with drift
BARS = {"drift": 1.1, "drift + scan matching": 1.6}


def with_localization(data: dict[str, Any], block: dict[str, Any]) -> dict[str, Any]:
    """``data`` with ``block`` as every robot's localisation."""
    return {**data, "team": {**data["team"], "localization": block}}


def runs(steps: int) -> dict[str, dict[str, Any]]:
    """Each configuration's scenario data."""
    exact = team_scenario(8, PRESET.map_path, PRESET.warmup + steps, PRESET)
    drift = {"odometry": {"alpha": ALPHA}}
    return {
        "exact": exact,
        "zero alphas": with_localization(exact, {"odometry": {"alpha": [0, 0, 0, 0]}}),
        "drift": with_localization(exact, drift),
        "drift + base": with_localization(
            exact, {**drift, "corrections": [{"kind": "base", "within": 40}]}
        ),
        "drift + teammate": with_localization(
            exact, {**drift, "corrections": [{"kind": "teammate"}]}
        ),
        "drift + scan matching": with_localization(
            exact, {**drift, "corrections": [{"kind": "scan_matching"}]}
        ),
    }


def main() -> None:
    """Print the medians and the ratios."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--steps", type=int, default=100)
    args = parser.parse_args()
    medians = step_medians(runs(args.steps), args.rounds, PRESET.warmup, args.steps)
    exact = statistics.median(medians["exact"])
    print(f"library, 8 robots, original settings, {args.rounds} interleaved rounds:")
    for name, values in medians.items():
        median = statistics.median(values)
        rounds = " / ".join(f"{v:.2f}" for v in values)
        bar = f" (bar <= {BARS[name]})" if name in BARS else ""
        print(f"  {name:>22}: {median:6.2f} ms per step, x{median / exact:.2f}{bar} ({rounds})")


if __name__ == "__main__":
    main()
