"""Benchmark of radio links (issue 32): what shadowing, bursts and a capacity cost a step.

The library team (8 and 32 robots, the original's settings, ``mresim bench --preset
original``) on the path-loss model, against the same team with shadowing (6 dB, 30 cells,
2 dB fading), Gilbert-Elliott bursts and a capacity of 20,000 bytes per step per link:
median ms per step and of the communication phase over the exploring phase, the runs
stepped in turn in one process (interleaved rounds), and each run's ratio to today's.
The bars: the communication phase <= 1.5, the whole step <= 1.15. The robots' knowledge
now moves more slowly, so the ratio holds what the radio does to the exploration too.

Run from the repository root: ``python benchmarks/bench_radio.py [--rounds 3]``.
"""

from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
from interleaved import phase_medians

from mresim_phys.output.bench import PRESETS, team_scenario

PRESET = PRESETS["original"]
RADIO = {
    "shadowing": {"sigma_db": 6.0, "length": 30.0, "fading_db": 2.0},
    "bursts": {"good_to_bad": 0.05, "bad_to_good": 0.3, "loss_bad": 0.8},
    "capacity": 20_000,
}
BARS = {"communication": 1.5, "step": 1.15}


def runs(robots: int, steps: int) -> dict[str, dict[str, Any]]:
    """Today's path-loss links and the radio, for a team of ``robots``."""
    today = team_scenario(robots, PRESET.map_path, PRESET.warmup + steps, PRESET)
    today = {**today, "communication": {"model": "path_loss"}}
    radio = {**today, "communication": {"model": "path_loss", **RADIO}}
    return {"today": today, "radio": radio}


def main() -> None:
    """Print the medians and the ratios."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--steps", type=int, default=100)
    parser.add_argument("--robots", type=int, nargs="+", default=[8, 32])
    args = parser.parse_args()
    for robots in args.robots:
        medians = phase_medians(
            runs(robots, args.steps), args.rounds, PRESET.warmup, args.steps, ("communication",)
        )
        print(f"library, {robots} robots, original settings, {args.rounds} interleaved rounds:")
        for measure, by_run in medians.items():
            today = statistics.median(by_run["today"])
            radio = statistics.median(by_run["radio"])
            rounds = " / ".join(f"{v:.2f}" for v in by_run["radio"])
            print(
                f"  {measure:>13}: today {today:6.2f} ms, radio {radio:6.2f} ms,"
                f" x{radio / today:.2f} (bar <= {BARS[measure]}; radio rounds {rounds})"
            )


if __name__ == "__main__":
    main()
