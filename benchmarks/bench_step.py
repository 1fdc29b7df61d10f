"""Whole-cycle benchmark: sensing and mapping kernels, and full steps on the office map.

Run ``python benchmarks/bench_step.py`` from the repository root (``--quick`` for fewer
repeats). Prints medians (not means: the machine is shared) of

* one 181-ray scan (pymunk, low-level call) and one map update from it (the numba
  kernel: scanline fill of cell centres + chord band + wall faces + safe space), at
  ranges 100 and 200 on ``maps/office.png``; the first map update of the process is
  timed on its own (numba compiles the kernel, or loads it from its on-disk cache);
* full simulation steps (motion + scans + replanning + comms + metrics) for teams of
  4 and 8 robots at speeds 3 and 6, measured over steps 50-250 of a frontier run.

A script, not a test: timings are reported in the issue notes and docs/performance.md.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from mresim_phys import Simulation  # noqa: E402
from mresim_phys.agents import empty_belief  # noqa: E402
from mresim_phys.knowledge.mapping import integrate_scan  # noqa: E402
from mresim_phys.scenario.load import validate_scenario  # noqa: E402
from mresim_phys.scenario.readers import load_image_map  # noqa: E402
from mresim_phys.world.sensing import Laser, scan  # noqa: E402
from mresim_phys.world.space import World  # noqa: E402

OFFICE = ROOT / "maps" / "office.png"


def free_poses(occupied: np.ndarray, n: int, seed: int = 0) -> list[tuple[float, float, float]]:
    """Random free poses at least 3 cells from any wall."""
    rng = np.random.default_rng(seed)
    rows, cols = np.nonzero(~occupied)
    poses = []
    while len(poses) < n:
        i = rng.integers(len(rows))
        r, c = rows[i], cols[i]
        if not occupied[max(r - 3, 0) : r + 4, max(c - 3, 0) : c + 4].any():
            poses.append((c + rng.random(), r + rng.random(), rng.uniform(-np.pi, np.pi)))
    return poses


def bench_kernels(repeats: int) -> None:
    occupied = load_image_map(OFFICE).occupied
    world = World(occupied, [])
    poses = free_poses(occupied, 200)
    flt = world.query_filter(None, robots_block=False)
    print("kernel (office 800x600, 200 poses)        median per call")
    x, y, h = poses[0]
    first_scan = scan(world, (x, y), h, Laser(range=100.0), flt)
    t0 = time.perf_counter()
    integrate_scan(*empty_belief(occupied.shape), first_scan, 0.1)
    print(f"  first map update (compile or cache load) {(time.perf_counter() - t0) * 1e3:8.0f} ms")
    for rng in (100.0, 200.0):
        sensor = Laser(range=rng)
        scans = [scan(world, (x, y), h, sensor, flt) for x, y, h in poses]
        t_scan, t_map = [], []
        for _ in range(repeats):
            t0 = time.perf_counter()
            for x, y, h in poses:
                scan(world, (x, y), h, sensor, flt)
            t_scan.append((time.perf_counter() - t0) / len(poses))
            belief, safe = empty_belief(occupied.shape)
            t0 = time.perf_counter()
            for result in scans:
                integrate_scan(belief, safe, result, 0.1)
            t_map.append((time.perf_counter() - t0) / len(poses))
        print(
            f"  scan, 181 rays, range {rng:>5.0f}"
            f"            {statistics.median(t_scan) * 1e6:8.0f} us"
        )
        print(
            f"  map update from it, range {rng:>5.0f}"
            f"        {statistics.median(t_map) * 1e6:8.0f} us"
        )


def team_scenario(robots: int, speed: float) -> dict:
    starts = [(40 + 10 * (i % 4), 290 + 10 * (i // 4)) for i in range(robots)]
    return {
        "name": "bench",
        "seed": 1,
        "steps": 250,
        "map": {"image": str(OFFICE)},
        "base_station": {"position": [25, 300], "comm_range": 150},
        "team": {"speed": speed, "radius": 2, "sensor": {"range": 100}, "comm_range": 150},
        "robots": [{"name": f"R{i}", "start": list(s)} for i, s in enumerate(starts)],
        "stop": {"all_done": False},
    }


def bench_steps(warmup: int, measured: int) -> None:
    print("full step (office, frontier, range 100)    median     p90      explored")
    for robots, speed in ((4, 3), (8, 3), (8, 6)):
        sim = Simulation(validate_scenario(team_scenario(robots, speed)))
        for _ in range(warmup):
            sim.step()
        times = []
        for _ in range(measured):
            t0 = time.perf_counter()
            sim.step()
            times.append(time.perf_counter() - t0)
        p90 = float(np.percentile(times, 90))
        print(
            f"  {robots} robots, speed {speed}"
            f"                 {statistics.median(times) * 1e3:6.1f} ms"
            f"  {p90 * 1e3:6.1f} ms   {sim.record.explored:.3f}"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer repeats and steps")
    args = parser.parse_args()
    bench_kernels(3 if args.quick else 7)
    bench_steps(20 if args.quick else 50, 60 if args.quick else 200)


if __name__ == "__main__":
    main()
