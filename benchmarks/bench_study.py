"""Benchmark of studies per hour: runs per core-hour of a shipped study, this tree against REV.

Users feel speed as studies per hour: a robustness study is 160 runs. Each round runs one
shard of the study (``mresim sweep STUDY --shard 0/N``: every N-th run, all arms and
seeds alike) with ``--workers`` local workers, once per build, each build a fresh
``mresim sweep`` process (imports, pool start, every run's world, log and outputs
included), the builds alternating so that a busy spell of a shared machine hits both
alike. Before the rounds, each build runs two runs untimed so that its kernels are
compiled. It prints each build's median wall time over the rounds, the runs per
core-hour (runs / (wall hours x workers)) and their ratio, with the per-round ratios.

Run from the repository root: ``python benchmarks/bench_study.py REV [--study PATH]
[--shard-of 5] [--workers 2] [--rounds 2]``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from worktree import checked_out

ROOT = Path(__file__).resolve().parent.parent
STUDY = ROOT / "studies" / "rooms_robustness.yaml"


def sweep_seconds(tree: Path, study: Path, shard: str, workers: int) -> tuple[float, int]:
    """Wall seconds of one ``mresim sweep`` of ``shard`` with the code of ``tree``, and the
    number of runs it finished."""
    cache = Path(tempfile.gettempdir()) / f"mresim-bench-numba-{tree.name}"
    env = {**os.environ, "PYTHONPATH": str(tree), "NUMBA_CACHE_DIR": str(cache)}
    with tempfile.TemporaryDirectory() as out:
        command = [sys.executable, "-m", "mresim_phys.launch", "sweep", str(study)]
        command += ["--shard", shard, "--workers", str(workers), "--out", out]
        started = time.perf_counter()
        subprocess.run(command, cwd=tempfile.gettempdir(), env=env, capture_output=True, check=True)
        seconds = time.perf_counter() - started
        runs = len(list(Path(out).glob("shards/*/runs/*/summary.json")))
    return seconds, runs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("rev", help="the commit to compare with (e.g. HEAD~5)")
    parser.add_argument("--study", type=Path, default=STUDY)
    parser.add_argument("--shard-of", type=int, default=5, help="time every N-th run")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--rounds", type=int, default=2)
    args = parser.parse_args()
    study = args.study.resolve()
    with checked_out(ROOT, args.rev, "bench_study.py") as old:
        builds = [("before", old), ("now", ROOT)]
        for _, tree in builds:  # compile each build's kernels, untimed
            sweep_seconds(tree, study, f"0/{args.shard_of * 16}", args.workers)
        seconds: dict[str, list[float]] = {"before": [], "now": []}
        runs = 0
        for k in range(args.rounds):
            for name, tree in builds if k % 2 == 0 else builds[::-1]:
                wall, runs = sweep_seconds(tree, study, f"0/{args.shard_of}", args.workers)
                seconds[name].append(wall)
                print(f"round {k + 1} {name}: {runs} runs in {wall:.1f} s", flush=True)
    report(args, seconds, runs)


def seconds_of(before: float, now: float) -> list[tuple[str, float]]:
    """The two builds' medians, named."""
    return [("before", before), ("now", now)]


def report(args: argparse.Namespace, seconds: dict[str, list[float]], runs: int) -> None:
    """Print the medians, runs per core-hour and the ratios."""
    before, now = statistics.median(seconds["before"]), statistics.median(seconds["now"])
    per_hour = {name: runs / (wall / 3600 * args.workers) for name, wall in seconds_of(before, now)}
    pairs = zip(seconds["now"], seconds["before"], strict=True)
    rounds = " ".join(f"{b / a:.2f}" for a, b in pairs)
    print(f"{args.study.name}, shard 0/{args.shard_of} ({runs} runs), {args.workers} workers")
    print(f"  before ({args.rev}): {before:.1f} s, {per_hour['before']:.0f} runs per core-hour")
    print(f"  now: {now:.1f} s, {per_hour['now']:.0f} runs per core-hour")
    print(f"  now / before runs per core-hour: {before / now:.2f} (per round {rounds})")


if __name__ == "__main__":
    main()
