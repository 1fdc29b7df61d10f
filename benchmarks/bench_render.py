"""Views benchmark (phase 8): rendering and encoding one 800x600 frame of an 8-robot run.

Run ``python benchmarks/bench_render.py`` from the repository root (``--quick`` for fewer
steps and repeats). Builds an 8-robot frontier run on ``maps/office.png`` (the team of
``bench_step.py``), runs it for 150 steps so beliefs, paths and frontiers are realistic,
then prints medians (not means: the machine is shared) of

* render with every layer on (free and safe space tints, frontier masks of all robots),
  the same snapshot rendered ``repeats`` times;
* render with the default layers, likewise;
* over the next ``repeats`` steps of the run (a new snapshot each time, so the encoder sees
  real motion): render (all layers), mp4v encode of that frame (``VideoRecorder`` into a
  temporary folder), and the two together.

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

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from bench_step import team_scenario  # noqa: E402

from mresim_phys import Simulation  # noqa: E402
from mresim_phys.load import validate_scenario  # noqa: E402
from mresim_phys.render import LayerSpec, Renderer  # noqa: E402
from mresim_phys.video import VideoRecorder  # noqa: E402


def summary(times_ms: list[float]) -> tuple[float, float]:
    """Median and p90 of a list of times."""
    times = sorted(times_ms)
    return statistics.median(times), times[int(0.9 * (len(times) - 1))]


def timed_ms(action: Callable[[], object]) -> float:
    t0 = time.perf_counter()
    action()
    return (time.perf_counter() - t0) * 1e3


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer steps and repeats")
    parser.add_argument("--scale", type=float, default=1.0, help="output pixels per cell")
    args = parser.parse_args()
    steps, repeats = (60, 10) if args.quick else (150, 30)
    sim = Simulation(validate_scenario(team_scenario(8, 3)))
    for _ in range(steps):
        sim.step()
    snap = sim.snapshot()
    every = Renderer(snap.truth.shape, LayerSpec.all(), args.scale)
    default = Renderer(snap.truth.shape, LayerSpec(), args.scale)
    width, height = every.size
    print(
        f"office {snap.truth.shape[1]}x{snap.truth.shape[0]}, 8 robots, step {snap.step}, "
        f"explored {snap.explored:.1%}; frame {width}x{height}, {repeats} repeats"
    )
    rows = {name: [] for name in ("all", "default", "live", "encode", "both")}
    for renderer, key in ((every, "all"), (default, "default")):
        renderer.render(snap)  # warm-up
        rows[key] = [timed_ms(lambda r=renderer: r.render(snap)) for _ in range(repeats)]
    with (
        tempfile.TemporaryDirectory() as folder,
        VideoRecorder(Path(folder) / "bench.mp4", 10, (width, height)) as video,
    ):
        video.write(every.render(snap))
        for _ in range(repeats):
            sim.step()
            t0 = time.perf_counter()
            frame = every.render(sim.snapshot())
            t1 = time.perf_counter()
            video.write(frame)
            t2 = time.perf_counter()
            rows["live"].append((t1 - t0) * 1e3)
            rows["encode"].append((t2 - t1) * 1e3)
            rows["both"].append((t2 - t0) * 1e3)
    names = {"all": "render, all layers", "default": "render, default layers"}
    names |= {"live": "render all, new step each time", "encode": "mp4v encode, one frame"}
    names["both"] = "render all + encode"
    print(f"  {'item':<34}{'median':>10}{'p90':>10}")
    for key, name in names.items():
        median, p90 = summary(rows[key])
        print(f"  {name:<34}{median:>8.2f} ms{p90:>7.2f} ms")


if __name__ == "__main__":
    main()
