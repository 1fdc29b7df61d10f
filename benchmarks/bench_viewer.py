"""Viewer benchmark (output edge): seeking a 3000-step office run log.

Run ``python benchmarks/bench_viewer.py [RUN_DIR]`` from the repository root. Without
``RUN_DIR`` it first runs ``scenarios/02_office_frontier.yaml`` for 3000 steps with its
stop rules off (about half a minute) into a temporary folder. It then times

* opening the log in the viewer (``ReplaySource.open``: one pass over the log that keeps
  a compressed keyframe every ``KEYFRAME_EVERY`` steps) and the keyframes' memory;
* ``--seeks`` random seeks (median, p95, max), alone and with the frame rendered with the
  default layers and encoded as PNG (what the page waits for);
* for comparison, reaching the last step without keyframes (a replay from step 0).

A script, not a test: the figures are in docs/viewer.md.
"""

from __future__ import annotations

import argparse
import random
import statistics
import sys
import tempfile
import time
from pathlib import Path

from mresim_phys.cli import main
from mresim_phys.output.runlog import Replay, RunLog
from mresim_phys.render import parse_layers
from mresim_phys.viewer.replaysource import KEYFRAME_EVERY, ReplaySource

SCENARIO = Path("scenarios/02_office_frontier.yaml")


def make_run(folder: Path) -> Path:
    """A 3000-step run of the office scenario with its stop rules off."""
    text = SCENARIO.read_text(encoding="utf-8").replace("../maps/", f"{Path.cwd()}/maps/")
    text = text.replace("stop: {explored: 0.95}", "stop: {all_done: false, stalled_for: null}")
    scenario = folder / "office3000.yaml"
    scenario.write_text(text, encoding="utf-8")
    out = folder / "run"
    code = main(
        ["run", str(scenario), "--steps", "3000", "--quiet", "--no-plots", "--out", str(out)]
    )
    if code != 0:
        sys.exit(code)
    return out


def spread(times: list[float]) -> str:
    """Median, p95 and max in milliseconds."""
    times = sorted(times)
    p95 = times[int(0.95 * (len(times) - 1))]
    median = statistics.median(times)
    return f"median {median * 1e3:.1f} ms, p95 {p95 * 1e3:.1f}, max {times[-1] * 1e3:.1f}"


def bench(run_dir: Path, seeks: int) -> None:
    started = time.perf_counter()
    source = ReplaySource.open(run_dir)
    opened = time.perf_counter() - started
    memory = sum(len(k) for k in source.index.keyframes.values()) / 1e6
    print(f"{run_dir}: {source.steps} logged steps")
    print(f"open + index: {opened:.2f} s; {len(source.index.keyframes)} keyframes every")
    print(f"  {KEYFRAME_EVERY} steps, {memory:.1f} MB compressed")
    source.warm_up()
    rng, layers = random.Random(1), parse_layers("default")
    only, framed = [], []
    for _ in range(seeks):
        n = rng.randrange(source.steps)
        t0 = time.perf_counter()
        source.snapshot(n)
        only.append(time.perf_counter() - t0)
        m = rng.randrange(source.steps)
        t0 = time.perf_counter()
        source.frame(m, layers, 0)
        framed.append(time.perf_counter() - t0)
    print(f"random seek: {spread(only)}")
    print(f"random seek + render + PNG: {spread(framed)}")
    log = RunLog.open(run_dir / "log")
    t0 = time.perf_counter()
    for _ in Replay(log).run():
        pass
    print(f"last step without keyframes (replay from step 0): {time.perf_counter() - t0:.2f} s")


def parse() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run_dir", type=Path, nargs="?", help="a run folder (default: make one)")
    parser.add_argument("--seeks", type=int, default=200, help="random seeks to time")
    return parser.parse_args()


if __name__ == "__main__":
    args = parse()
    if args.run_dir is not None:
        bench(args.run_dir, args.seeks)
    else:
        with tempfile.TemporaryDirectory() as tmp:
            bench(make_run(Path(tmp)), args.seeks)
