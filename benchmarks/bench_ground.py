"""Benchmark of ground classes (issue 33): what each robot's own passable set costs a step.

The library team (8 robots, the original's settings, ``mresim bench --preset original``)
on its map as it is, against the same team on the map with three ground classes (rubble
in the west and east wings, stairs across the middle, a pool in the north; about 17 % of
the map): half the team (R0-R3) can enter none of them, the other half crosses everything at full
speed. Each robot then plans on its own passable set. (A robot that crosses a class slowly
plans with weighted costs, as with ``terrain:``; ``--slow`` gives R0-R3 rubble at half
speed instead, to time that too.) Median ms per step and of the planning
phase over the exploring phase, the runs stepped in turn in one process (interleaved
rounds), and the ratio to the plain map. The bar: the whole step <= 1.15. The robots'
paths now differ, so the ratio holds what the ground does to the exploration too.

Run from the repository root: ``python benchmarks/bench_ground.py [--rounds 3]``.
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
GROUND = {
    "classes": {"rubble": 0.0, "stairs": 0.0, "pool": 0.0},
    "regions": [
        {"ground": "rubble", "box": [40, 120, 200, 480]},
        {"ground": "rubble", "box": [600, 120, 760, 480]},
        {"ground": "stairs", "box": [360, 200, 440, 400]},
        {"ground": "pool", "circle": [400, 80, 50]},
    ],
}
ALL = {"rubble": 1.0, "stairs": 1.0, "pool": 1.0}
BAR = 1.15


def runs(robots: int, steps: int, slow: bool) -> dict[str, dict[str, Any]]:
    """The plain map and the map with ground classes, for a team of ``robots``."""
    plain = team_scenario(robots, PRESET.map_path, PRESET.warmup + steps, PRESET)
    team = [dict(r, crosses=ALL) if i >= robots // 2 else r for i, r in enumerate(plain["robots"])]
    classes = {**GROUND["classes"], "rubble": 0.5} if slow else GROUND["classes"]
    return {
        "plain": plain,
        "ground": {**plain, "ground": {**GROUND, "classes": classes}, "robots": team},
    }


def main() -> None:
    """Print the medians and the ratios."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--steps", type=int, default=100)
    parser.add_argument("--robots", type=int, default=8)
    parser.add_argument("--slow", action="store_true", help="R0-R3 cross rubble at half speed")
    args = parser.parse_args()
    scenarios = runs(args.robots, args.steps, args.slow)
    medians = phase_medians(scenarios, args.rounds, PRESET.warmup, args.steps, ("planning",))
    print(f"library, {args.robots} robots, original settings, {args.rounds} interleaved rounds:")
    print_ratios(medians, "plain", "ground", BAR)


if __name__ == "__main__":
    main()
