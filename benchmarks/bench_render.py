"""Views benchmark (phase 8): rendering and encoding 800x600 frames of a running 8-robot run.

Run ``python benchmarks/bench_render.py`` from the repository root (``--quick`` for fewer
frames). Builds an 8-robot frontier run on ``maps/office.png`` (the team of
``bench_step.py``), runs it for 150 steps so beliefs, paths and frontiers are realistic,
then, for each of the next ``--frames`` steps (at least 100; a new snapshot every frame,
as in a run with a video every step, so caches are cold and the encoder sees real
motion), times

* the snapshot and its render with every layer on (free and safe space tints, frontiers
  of all robots, comm ranges, links, paths, names, header, legend);
* the mp4v encode of that frame (a plain ``cv2.VideoWriter`` into a temporary folder,
  timed to the end of the encode: ``VideoRecorder`` encodes in a background thread);
* the two together (the issue's target: a median under 6 ms).

It prints the median and p90 of each (not means: the machine is shared), then the same
snapshot rendered again and again with all and with the default layers, for comparison.
``--overhead`` also times ``run_session`` on ``scenarios/02_office_frontier.yaml`` for 300
steps with and without a video every step (interleaved, ``--runs`` each; the issue's
target: at most 1.5x).

A script, not a test: timings are reported in the issue notes and docs/performance.md.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import cv2

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from bench_step import team_scenario  # noqa: E402

from mresim_phys import Simulation  # noqa: E402
from mresim_phys.output.session import run_session  # noqa: E402
from mresim_phys.render import LayerSpec, Renderer  # noqa: E402
from mresim_phys.scenario.load import validate_scenario  # noqa: E402

OFFICE_RUN = ROOT / "scenarios" / "02_office_frontier.yaml"


def summary(times_ms: list[float]) -> tuple[float, float]:
    """Median and p90 of a list of times."""
    times = sorted(times_ms)
    return statistics.median(times), times[int(0.9 * (len(times) - 1))]


def timed_ms(action: Callable[[], object]) -> float:
    t0 = time.perf_counter()
    action()
    return (time.perf_counter() - t0) * 1e3


def fresh_frames(sim: Simulation, renderer: Renderer, frames: int) -> dict[str, list[float]]:
    """Step, snapshot, render and encode ``frames`` times; times per frame in ms."""
    rows: dict[str, list[float]] = {"render": [], "encode": [], "both": []}
    with tempfile.TemporaryDirectory() as folder:
        code = cv2.VideoWriter.fourcc(*"mp4v")
        video = cv2.VideoWriter(str(Path(folder) / "bench.mp4"), code, 20.0, renderer.size)
        video.write(renderer.render(sim.snapshot()))
        for _ in range(frames):
            sim.step()
            t0 = time.perf_counter()
            frame = renderer.render(sim.snapshot())
            t1 = time.perf_counter()
            video.write(frame)
            t2 = time.perf_counter()
            rows["render"].append((t1 - t0) * 1e3)
            rows["encode"].append((t2 - t1) * 1e3)
            rows["both"].append((t2 - t0) * 1e3)
        video.release()
    return rows


def session_seconds(video: Path | None, steps: int) -> float:
    """Wall time of ``run_session`` on scenario 02 (metrics, run log, final PNG, video?)."""
    render = {"video": str(video) if video else False, "every": 1, "plots": False}
    sim = Simulation.from_yaml(OFFICE_RUN, steps=steps, render=render)
    with tempfile.TemporaryDirectory() as folder:
        t0 = time.perf_counter()
        run_session(sim, Path(folder) / "run")
        return time.perf_counter() - t0


def overhead(steps: int, runs: int) -> None:
    """Print the wall time of runs with and without a video every step, and their ratio."""
    times: dict[bool, list[float]] = {False: [], True: []}
    with tempfile.TemporaryDirectory() as folder:
        session_seconds(Path(folder) / "warm.mp4", 20)  # numba cache loads, imports
        for _ in range(runs):
            for with_video in (False, True):
                video = Path(folder) / "run.mp4" if with_video else None
                times[with_video].append(session_seconds(video, steps))
    plain, video = (statistics.median(times[v]) for v in (False, True))
    print(f"scenario 02, {steps} steps, {runs} interleaved runs each (median wall time)")
    print(f"  without video {plain:6.2f} s   runs {', '.join(f'{t:.2f}' for t in times[False])}")
    print(f"  video / step  {video:6.2f} s   runs {', '.join(f'{t:.2f}' for t in times[True])}")
    print(f"  ratio {video / plain:.2f}x (target: at most 1.5x)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer warm-up steps, 100 frames")
    parser.add_argument("--frames", type=int, default=200, help="fresh frames (at least 100)")
    parser.add_argument("--scale", type=float, default=1.0, help="output pixels per cell")
    parser.add_argument("--overhead", action="store_true", help="also time scenario 02 runs")
    parser.add_argument("--runs", type=int, default=3, help="runs each, with --overhead")
    args = parser.parse_args()
    steps, frames = (60, 100) if args.quick else (150, max(args.frames, 100))
    sim = Simulation(validate_scenario(team_scenario(8, 3)))
    for _ in range(steps):
        sim.step()
    snap = sim.snapshot()
    every = Renderer(snap.truth.shape, LayerSpec.all(), args.scale)
    default = Renderer(snap.truth.shape, LayerSpec(), args.scale)
    width, height = every.size
    print(
        f"office {snap.truth.shape[1]}x{snap.truth.shape[0]}, 8 robots, steps {snap.step + 1}-"
        f"{snap.step + frames}, explored {snap.explored:.1%} at the start; frame {width}x{height}"
        f", {frames} fresh frames; cv2 threads {cv2.getNumThreads()}"
    )
    rows = fresh_frames(sim, every, frames)
    snap = sim.snapshot()
    for renderer, key in ((every, "all"), (default, "default")):
        renderer.render(snap)  # warm-up
        rows[key] = [timed_ms(lambda r=renderer: r.render(snap)) for _ in range(frames)]
    names = {"render": "snapshot + render, all layers", "encode": "mp4v encode"}
    names["both"] = "render + encode (target < 6 ms)"
    names |= {"all": "same snapshot again, all layers", "default": "same snapshot, default"}
    print(f"  {'new step every frame':<36}{'median':>10}{'p90':>10}")
    for key, name in names.items():
        if key == "all":
            print(f"  {'one snapshot, rendered repeatedly':<36}")
        median, p90 = summary(rows[key])
        print(f"  {name:<36}{median:>7.2f} ms{p90:>7.2f} ms")
    if args.overhead:
        overhead(300, args.runs)


if __name__ == "__main__":
    main()
