"""Benchmark of sweeps: wall time of one small study with 1 and with 2 local workers.

The study: scenario 13 (rooms, 4 frontier robots) x comm range 150 / 200 x seeds 0-7, step
cap 200 (16 runs of 140-190 steps, about 4 s each on one free core). Each round runs
``mresim sweep`` as a fresh process (start-up, checks, pool, runs and tables included)
into a fresh folder with ``--workers 1`` and ``--workers 2``, alternating which goes
first; the report gives each round's times, the median of each, their ratio and the
1-minute load average before each sweep (the machine may be shared: a load above the
sweep's own workers means other work took cores).

Run from the repository root: ``python benchmarks/bench_sweep.py [--rounds 3]``.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path
from time import perf_counter

import yaml

ROOT = Path(__file__).resolve().parent.parent
STUDY = {
    "name": "bench-sweep",
    "scenarios": [str(ROOT / "scenarios" / "13_rooms_4_robots.yaml")],
    "axes": {"team.comm_range": [150, 200]},
    "seeds": 8,
    "steps": 200,
}


def load() -> float:
    """The 1-minute load average."""
    return os.getloadavg()[0]


def time_sweep(study: Path, out: Path, workers: int) -> tuple[float, float]:
    """(seconds, load before) of one ``mresim sweep`` into a fresh ``out``."""
    shutil.rmtree(out, ignore_errors=True)
    before = load()
    started = perf_counter()
    command = [sys.executable, "-m", "mresim_phys.cli", "sweep", str(study), "--out", str(out)]
    subprocess.run([*command, "--workers", str(workers), "--quiet"], check=True)
    return perf_counter() - started, before


def main() -> None:
    """Time the rounds and print the report."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3)
    rounds = parser.parse_args().rounds
    times: dict[int, list[float]] = {1: [], 2: []}
    with tempfile.TemporaryDirectory() as folder:
        study = Path(folder) / "study.yaml"
        study.write_text(yaml.safe_dump(STUDY), encoding="utf-8")
        for k in range(rounds):
            for workers in (1, 2) if k % 2 == 0 else (2, 1):
                seconds, before = time_sweep(study, Path(folder) / "out", workers)
                times[workers].append(seconds)
                print(f"round {k + 1}: {workers} worker(s) {seconds:6.1f} s (load {before:.2f})")
    one, two = statistics.median(times[1]), statistics.median(times[2])
    print(f"median: 1 worker {one:.1f} s, 2 workers {two:.1f} s, speed-up {one / two:.2f}x")


if __name__ == "__main__":
    main()
