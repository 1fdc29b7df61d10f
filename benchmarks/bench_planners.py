"""Benchmark of the phase 4b path planners on fully known maps (the worst case).

Prints the median of ``--repeats`` runs (``time.perf_counter``, wall clock) of:

* ``astar`` and ``jps`` corner to corner (with their expansion counts), and the
  ``distance_field`` from the corner (every reachable cell);
* the topological map rebuild (``build_map``: skeleton, nodes, regions, graph, boxes) and a
  corner-to-corner topological query on it (anchors, graph route, corridor search);
* line-of-sight smoothing of the corner-to-corner path;

on ``office`` (maps/office.png, 800x600), two open maps, ``rubble`` (maps/rubble.png,
500x400) and ``pillars800`` (800x600, 200 round pillars), then ``maze2000`` (2000x2000 maze,
40-cell pitch) and ``open2000`` (2000x2000, 400 pillars); the synthetic maps are drawn by
benchmarks/bench_planning.py's generators. Then, on every shipped map, the
length of topological paths over optimal ones for random pairs of passable cells (sum over
pairs, mean and worst pair) and corner to corner.

Clearance 3.0 (the default robot radius 2 + wall margin 1). Run from the repository root:
``PYTHONPATH=. python benchmarks/bench_planners.py [--skip-big] [--repeats 7] [--pairs 40]``.
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
from bench_planning import corners, known_belief, make_maze, make_open

from mresim_phys.planning.astar import astar_search
from mresim_phys.planning.fields import distance_field, path_length, traversable
from mresim_phys.planning.grid import Window
from mresim_phys.planning.jps import jps_search
from mresim_phys.planning.smoothing import smooth_path
from mresim_phys.planning.topobuild import build_map
from mresim_phys.planning.topological import topological_path
from mresim_phys.scenario.readers import load_image_map, load_ros_map, load_text_map
from mresim_phys.types import BoolGrid

CLEARANCE = 3.0
SPACING = 10  # the topological planner's default node_spacing
MAPS = Path(__file__).resolve().parent.parent / "maps"


def median_ms(fn: Callable[[], object], repeats: int) -> float:
    """Median wall time of ``repeats`` calls, in ms."""
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return 1e3 * statistics.median(times)


def bench_map(name: str, occupied: BoolGrid, repeats: int) -> None:
    """Print the planner medians for one fully known map."""
    passable = traversable(known_belief(occupied), CLEARANCE)
    start_xy, goal = corners(passable)
    start = (int(start_xy[1]), int(start_xy[0]))
    a_path, a_count = astar_search(_window(passable), start, goal)
    _, j_count = jps_search(_window(passable), start, goal)
    topo = build_map(passable, SPACING)
    rows, cols = occupied.shape
    print(f"\n{name} {cols}x{rows}: {passable.mean():.0%} passable, corner-to-corner cost "
          f"{path_length(a_path):.1f}; {topo.node_count} nodes")  # fmt: skip
    kernels: list[tuple[str, Callable[[], object]]] = [
        (f"astar corner to corner ({a_count} expansions)",
         lambda: astar_search(_window(passable), start, goal)),
        (f"jps corner to corner ({j_count} expansions)",
         lambda: jps_search(_window(passable), start, goal)),
        ("distance_field from the corner", lambda: distance_field(passable, start_xy)),
        ("topological rebuild", lambda: build_map(passable, SPACING)),
        ("topological query corner to corner (corridor 1)",
         lambda: topological_path(topo, passable, start, goal, 1)),
        ("topological query corner to corner (corridor 0)",
         lambda: topological_path(topo, passable, start, goal, 0)),
        ("smoothing the corner-to-corner path", lambda: smooth_path(a_path, passable)),
    ]  # fmt: skip
    for label, fn in kernels:
        print(f"  {label:<52} {median_ms(fn, repeats):9.2f} ms")


def _window(passable: BoolGrid) -> Window:
    window = Window.of(passable)
    assert window is not None
    return window


def shipped() -> dict[str, BoolGrid]:
    """Ground truth of every shipped map."""
    return {
        "office": load_image_map(MAPS / "office.png").occupied,
        "maze": load_image_map(MAPS / "maze.png").occupied,
        "rubble": load_image_map(MAPS / "rubble.png").occupied,
        "small_rooms": load_image_map(MAPS / "small_rooms.png").occupied,
        "cave": load_text_map(MAPS / "cave.txt").occupied,
        "warehouse": load_ros_map(MAPS / "warehouse.yaml").occupied,
    }


def ratios(occupied: BoolGrid, pairs: int) -> tuple[float, float, float, float]:
    """Topological over optimal length: (sum ratio, mean, worst pair, corner to corner).

    The corner-to-corner ratio is nan when the two corner cells are not connected.
    """
    passable = traversable(known_belief(occupied), CLEARANCE)
    topo = build_map(passable, SPACING)
    rows, cols = np.nonzero(passable)
    rng = np.random.default_rng(0)
    found, best = [], []
    while len(found) < pairs:
        i, j = rng.integers(len(rows), size=2)
        start, goal = (int(rows[i]), int(cols[i])), (int(rows[j]), int(cols[j]))
        optimal = distance_field(passable, (start[1] + 0.5, start[0] + 0.5)).costs[goal]
        if np.isfinite(optimal) and optimal >= 1.0:
            found.append(path_length(topological_path(topo, passable, start, goal)))
            best.append(optimal)
    start_xy, goal = corners(passable)
    start = (int(start_xy[1]), int(start_xy[0]))
    c2c_best = distance_field(passable, start_xy).costs[goal]
    c2c = np.nan
    if np.isfinite(c2c_best):
        c2c = path_length(topological_path(topo, passable, start, goal)) / c2c_best
    each = np.array(found) / np.array(best)
    return sum(found) / sum(best), float(each.mean()), float(each.max()), c2c


def main() -> None:
    """Run the benchmark."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--skip-big", action="store_true", help="skip the 2000x2000 maps")
    parser.add_argument("--repeats", type=int, default=7, help="runs per median")
    parser.add_argument("--pairs", type=int, default=40, help="random pairs per shipped map")
    args = parser.parse_args()
    warm = np.ones((8, 8), dtype=bool)
    t0 = time.perf_counter()
    astar_search(_window(warm), (1, 1), (6, 6)), jps_search(_window(warm), (1, 1), (6, 6))
    topological_path(build_map(warm, 4), warm, (1, 1), (6, 6))
    print(f"first calls (numba compile or cache load): {1e3 * (time.perf_counter() - t0):.0f} ms")
    print(f"median of {args.repeats} runs, clearance {CLEARANCE}, node spacing {SPACING}")
    maps = shipped()
    bench_map("office", maps["office"], args.repeats)
    bench_map("rubble", maps["rubble"], args.repeats)
    bench_map("pillars800", make_open(800, 600, discs=200), args.repeats)
    if not args.skip_big:
        bench_map("maze2000", make_maze(2000, 2000, pitch=40, wall=4), args.repeats)
        bench_map("open2000", make_open(2000, 2000, discs=400), args.repeats)
    print(f"\ntopological / optimal path length, {args.pairs} random pairs per map")
    print(f"  {'map':<12} {'sum':>7} {'mean':>7} {'worst':>7} {'corner':>7}")
    for name, occupied in maps.items():
        total, mean, worst, c2c = ratios(occupied, args.pairs)
        print(f"  {name:<12} {total:7.4f} {mean:7.4f} {worst:7.4f} {c2c:7.4f}")
    print("  (topological planner defaults: node spacing 10, corridor 1)")


if __name__ == "__main__":
    main()
