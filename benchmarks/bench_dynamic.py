"""Benchmark of the dynamic world: what moving obstacles, doors and debris cost.

1. A step of the library team (8 robots, the original's settings, ``mresim bench --preset
   original``) in the static library and with 20 moving obstacles (discs of radius 2 on
   seeded random walks, speed 1) and 2 doors on a cycle: median ms per step over the
   exploring phase, each run stepped in turn in one process (interleaved rounds), and
   the ratio (the dynamic-world issue's bar: <= 1.25). Two more runs split the cost: the
   static library with ``belief: latest`` (the bookkeeping a changing world needs), and
   the dynamic one with its doors but no obstacles.
2. One debris event (a 6x6 piece of rubble through the events' context: the truth, the
   Space's segments, the reachable set and the explored count follow) on the 800x600
   library and on the library tiled to 2000x2000 (``bench_scale.large_library``): median
   ms (bars: <= 5 ms and <= 20 ms).

Run from the repository root: ``python benchmarks/bench_dynamic.py [--rounds 3]``.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
from pathlib import Path
from time import perf_counter
from typing import Any

import numpy as np
from scipy import ndimage

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_scale import large_library
from interleaved import step_medians as interleaved_medians

from mresim_phys.output.bench import PRESETS, team_scenario
from mresim_phys.scenario.load import validate_scenario
from mresim_phys.scenario.readers import load_image_map
from mresim_phys.sim import Simulation
from mresim_phys.world.debris import square_at

PRESET = PRESETS["original"]
OBSTACLES, DOORS = 20, 2


def open_spots(map_path: Path, count: int, seed: int = 5) -> list[tuple[float, float]]:
    """``count`` cell centres at least 6 cells from any wall, drawn with a fixed seed."""
    occupied = load_image_map(map_path).occupied
    clear = np.argwhere(ndimage.distance_transform_edt(~occupied) > 6)
    picks = np.random.default_rng(seed).choice(len(clear), count, replace=False)
    return [(float(clear[i][1]) + 0.5, float(clear[i][0]) + 0.5) for i in picks]


def dynamic_scenario(robots: int, steps: int) -> dict[str, Any]:
    """The library team with moving obstacles and cycling doors."""
    data = team_scenario(robots, PRESET.map_path, steps, PRESET)
    spots = open_spots(PRESET.map_path, OBSTACLES + DOORS)
    data["obstacles"] = [
        {"name": f"walker_{i}", "shape": {"circle": 2}, "motion": {"random_walk": list(p)}}
        for i, p in enumerate(spots[:OBSTACLES])
    ]
    data["doors"] = [
        {"name": f"door_{i}", "between": [[x - 8, y], [x + 8, y]], "period": 60, "open_for": 40}
        for i, (x, y) in enumerate(spots[OBSTACLES:])
    ]
    return data


def step_medians(rounds: int, robots: int, steps: int) -> dict[str, list[float]]:
    """Per round, the median ms per step of the static and the dynamic run."""
    static = team_scenario(robots, PRESET.map_path, PRESET.warmup + steps, PRESET)
    dynamic = dynamic_scenario(robots, PRESET.warmup + steps)
    runs = {
        "static": static,
        "dynamic": dynamic,
        # the decomposition: what 'latest' beliefs cost alone, and with the doors only
        "static, latest beliefs": {
            **static,
            "simulation": {**static["simulation"], "belief": "latest"},
        },
        "doors only": {**dynamic, "obstacles": []},
    }
    return interleaved_medians(runs, rounds, PRESET.warmup, steps)


def debris_ms(map_path: Path, repeats: int = 30) -> float:
    """Median ms of one 6x6 rubble piece through a run's events' context."""
    data = team_scenario(8, map_path, 10, PRESET)
    sim = Simulation(validate_scenario(data))
    spots = open_spots(map_path, repeats, seed=9)
    times = []
    for x, y in spots:
        mask = square_at(sim.world.shape, int(y), int(x), 6)
        started = perf_counter()
        sim._events.change_cells(mask, True, "avoid")
        times.append(perf_counter() - started)
    return 1e3 * statistics.median(times)


def main() -> None:
    """Print both parts."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--steps", type=int, default=100)
    args = parser.parse_args()
    medians = step_medians(args.rounds, 8, args.steps)
    static, dynamic = (statistics.median(medians[n]) for n in ("static", "dynamic"))
    print(f"library, 8 robots, original settings, {args.rounds} interleaved rounds:")
    for name, values in medians.items():
        rounds = " / ".join(f"{v:.2f}" for v in values)
        print(f"  {name:>22}: median {statistics.median(values):6.2f} ms per step ({rounds})")
    ratio = dynamic / static
    print(f"  {OBSTACLES} obstacles + {DOORS} doors / static = {ratio:.2f} (bar <= 1.25)")
    with tempfile.TemporaryDirectory() as tmp:
        big = large_library(Path(tmp) / "big.png")
        for label, path in (("800x600", PRESET.map_path), ("2000x2000", big)):
            print(f"  a 6x6 debris event, {label}: {debris_ms(path):.2f} ms (median)")


if __name__ == "__main__":
    main()
