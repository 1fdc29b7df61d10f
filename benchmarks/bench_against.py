"""Benchmark of the whole step against an earlier commit: this tree and REV, in turn.

A commit that claims a speed-up measures it here: REV is checked out into a temporary git
worktree, and every round runs each (team size, thread count) once per build, each run in
its own fresh process (``mresim_phys.output.bench.time_team`` at the ``original`` preset:
the library, speed 10, laser 200, comm 200), the builds alternating so that a busy spell
of a shared machine hits both alike. It prints, per configuration, each build's median
over rounds of the per-run median ms per step, their ratio, and the per-round ratios.

Run from the repository root: ``python benchmarks/bench_against.py REV [--robots 8,16,32]
[--threads 1,2] [--rounds 4] [--map PATH]``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from worktree import checked_out

ROOT = Path(__file__).resolve().parent.parent
ONE_RUN = """
import sys
from pathlib import Path
from mresim_phys.output.bench import PRESETS, time_team
robots, threads, map_path = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
preset = PRESETS["original"]
path = Path(map_path) if map_path else preset.map_path
print(time_team(robots, path, preset.warmup, preset.steps, preset, (threads,))[0].median_ms)
"""


def numbers(text: str) -> list[int]:
    """A comma-separated list of whole numbers."""
    return [int(part) for part in text.split(",") if part.strip()]


def median_ms(tree: Path, robots: int, threads: int, map_path: str) -> float:
    """One run's median ms per step with the code of ``tree``, in a fresh process."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    out = subprocess.run(
        [sys.executable, "-c", ONE_RUN, str(robots), str(threads), map_path],
        cwd=tempfile.gettempdir(),  # not the repository: PYTHONPATH decides the build
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    return float(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("rev", help="the commit to compare with (e.g. HEAD~5)")
    parser.add_argument("--robots", type=numbers, default=[8, 16, 32])
    parser.add_argument("--threads", type=numbers, default=[1, 2])
    parser.add_argument("--rounds", type=int, default=4)
    parser.add_argument("--map", default="", help="map image (default: the preset's)")
    args = parser.parse_args()
    with checked_out(ROOT, args.rev, "bench_against.py") as old:
        compare(old, args)


def compare(old: Path, args: argparse.Namespace) -> None:
    """Alternate the builds over the rounds and print the medians and ratios."""
    configs = [(r, t) for r in args.robots for t in args.threads]
    times: dict[tuple[str, int, int], list[float]] = {}
    for k in range(args.rounds):
        for robots, threads in configs:
            builds = [("before", old), ("now", ROOT)]
            for name, tree in builds if k % 2 == 0 else builds[::-1]:
                ms = median_ms(tree, robots, threads, args.map)
                times.setdefault((name, robots, threads), []).append(ms)
    print(f"ms per step, {args.rev} (before) and this tree (now), {args.rounds} rounds")
    print(" robots threads   before      now  now/before  per round")
    for robots, threads in configs:
        before, now = times["before", robots, threads], times["now", robots, threads]
        rounds = " ".join(f"{b / a:.2f}" for a, b in zip(before, now, strict=True))
        a, b = statistics.median(before), statistics.median(now)
        print(f"{robots:>7} {threads:>7} {a:8.2f} {b:8.2f} {b / a:11.2f}  {rounds}")


if __name__ == "__main__":
    main()
