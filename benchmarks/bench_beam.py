"""Benchmark of the laser beam model (issue 33): what noisy readings and mapping by evidence
cost a step.

The library team (8 robots, the original's settings, ``mresim bench --preset original``)
with exact lasers, against the same team whose lasers read through the beam model of
scenario 31 (80 % hits with 0.3 cells of noise, 5 % short, 10 % no return, 5 % random; a
speckle filter; no-return rays free 30 cells) and map by evidence: median ms per step and
of the sensing phase (scans cast, read and folded) and planning over the exploring phase,
the runs stepped in turn in one process (interleaved rounds), and each run's ratio to the
exact one. The bar: the whole
step <= 1.1. The robots' maps now grow differently, so the ratio holds what the noise does
to the exploration too.

Run from the repository root: ``python benchmarks/bench_beam.py [--rounds 3]``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
from interleaved import phase_medians, print_ratios

from mresim_phys.output.bench import PRESETS, team_scenario

PRESET = PRESETS["original"]
BEAM = {
    "z_hit": 0.8, "z_short": 0.05, "z_max": 0.1, "z_rand": 0.05, "sigma_hit": 0.3,
    "max_free": 30, "speckle": 1.5,
}  # fmt: skip
BAR = 1.1


def runs(robots: int, steps: int) -> dict[str, dict[str, Any]]:
    """Exact lasers and beam-model lasers, for a team of ``robots``."""
    exact = team_scenario(robots, PRESET.map_path, PRESET.warmup + steps, PRESET)
    team = exact["team"]
    beam = {**exact, "team": {**team, "sensor": {**team["sensor"], "beam": BEAM}}}
    return {"exact": exact, "beam": beam}


def main() -> None:
    """Print the medians and the ratios."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--steps", type=int, default=100)
    parser.add_argument("--robots", type=int, default=8)
    args = parser.parse_args()
    phases = ("sensing", "planning")  # a turn's queued scans cast, read and fold as sensing
    medians = phase_medians(
        runs(args.robots, args.steps), args.rounds, PRESET.warmup, args.steps, phases
    )
    print(f"library, {args.robots} robots, original settings, {args.rounds} interleaved rounds:")
    print_ratios(medians, "exact", "beam", BAR)


if __name__ == "__main__":
    main()
