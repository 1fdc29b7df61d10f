"""Views benchmark (phase 8): rendering and encoding one 800x600 frame of an 8-robot run.

Run ``python benchmarks/bench_render.py`` from the repository root (``--quick`` for fewer
steps and repeats). Builds an 8-robot frontier run on ``maps/office.png`` (the team of
``bench_step.py``), runs it for 150 steps so beliefs, paths and frontiers are realistic,
then prints medians (not means: the machine is shared) of

* render with every layer on (free and safe space tints, frontier masks of all robots);
* render with the default layers;
* mp4v encode of one frame (``VideoRecorder`` into a temporary folder);
* render (all layers) + encode.

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


def median_ms(action: Callable[[], object], repeats: int) -> tuple[float, float]:
    """Median and p90 wall time of ``action`` in milliseconds (after one warm-up call)."""
    action()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        action()
        times.append((time.perf_counter() - t0) * 1e3)
    times.sort()
    return statistics.median(times), times[int(0.9 * (len(times) - 1))]


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
    frame = every.render(snap)
    height, width = frame.shape[:2]
    print(
        f"office {snap.truth.shape[1]}x{snap.truth.shape[0]}, 8 robots, step {snap.step}, "
        f"explored {snap.explored:.1%}; frame {width}x{height}, {repeats} repeats"
    )
    print(f"  {'item':<34}{'median':>10}{'p90':>10}")
    rows = [("render, all layers", lambda: every.render(snap))]
    rows.append(("render, default layers", lambda: default.render(snap)))
    with tempfile.TemporaryDirectory() as folder:
        video = VideoRecorder(Path(folder) / "bench.mp4", 10, (width, height))
        rows.append(("mp4v encode (one frame)", lambda: video.write(frame)))
        rows.append(("render all + encode", lambda: video.write(every.render(snap))))
        for name, action in rows:
            median, p90 = median_ms(action, repeats)
            print(f"  {name:<34}{median:>8.2f} ms{p90:>7.2f} ms")
        video.close()


if __name__ == "__main__":
    main()
