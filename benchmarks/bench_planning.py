"""Benchmark of phases 3b (frontiers) and 4b (planning) on synthetic maps.

Prints the median of 7 runs (``time.perf_counter``, wall clock) for each kernel on:

* ``maze800``: 800x600, 25-cell-pitch maze, 3-cell walls, ~12% of inner walls removed (loops);
* ``open800``: 800x600 with a 3-cell border and 40 discs;
* ``maze2000``: 2000x2000, 40-cell pitch, 4-cell walls (like ``big2000`` in the perf notes).

Fully known maps are used for C-space, distance fields and paths (the worst case). For
frontiers, a 35%-known belief keeps the cells nearest to 10 seed points. For comparison it
also times ``skimage.graph.MCP_Geometric``, the engine the design notes measured. The first
line gives the cost of the first search in a process: the numba JIT compile, or loading the
compiled kernel from the on-disk cache when a previous process compiled it.

Run from the repository root: ``PYTHONPATH=. python benchmarks/bench_planning.py [--skip-big]``
(or without ``PYTHONPATH`` once the package is installed).
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable

import cv2
import numpy as np
from skimage.graph import MCP_Geometric

from mresim_phys.knowledge.frontiers import find_frontiers
from mresim_phys.knowledge.targets import frontier_targets
from mresim_phys.planning.fields import distance_field, plan_path, traversable
from mresim_phys.types import FREE, OCCUPIED, UNKNOWN, BeliefGrid, BoolGrid

CLEARANCE = 2.2  # robot radius 1.5 + 0.71 margin
REPEATS = 7


def make_maze(
    width: int, height: int, pitch: int, wall: int, loops: float = 0.12, seed: int = 0
) -> BoolGrid:
    """Occupancy of a depth-first-search maze with extra openings (True = wall)."""
    rng = np.random.default_rng(seed)
    ny, nx = height // pitch, width // pitch
    occ = np.zeros((height, width), dtype=bool)
    occ[:wall], occ[-wall:], occ[:, :wall], occ[:, -wall:] = True, True, True, True
    right = np.ones((ny, nx), dtype=bool)  # wall on the right of maze cell (i, j)
    down = np.ones((ny, nx), dtype=bool)  # wall below maze cell (i, j)
    seen = np.zeros((ny, nx), dtype=bool)
    stack = [(0, 0)]
    seen[0, 0] = True
    while stack:  # loop over maze cells (768 / 2500), not grid cells
        i, j = stack[-1]
        options = [
            (i + di, j + dj)
            for di, dj in ((0, 1), (1, 0), (0, -1), (-1, 0))
            if 0 <= i + di < ny and 0 <= j + dj < nx and not seen[i + di, j + dj]
        ]
        if not options:
            stack.pop()
            continue
        a, b = options[int(rng.integers(len(options)))]
        if a == i:
            right[i, min(j, b)] = False
        else:
            down[min(i, a), j] = False
        seen[a, b] = True
        stack.append((a, b))
    right &= rng.random((ny, nx)) > loops
    down &= rng.random((ny, nx)) > loops
    for i, j in zip(*np.nonzero(right[:, :-1]), strict=True):
        occ[i * pitch : (i + 1) * pitch + wall, (j + 1) * pitch : (j + 1) * pitch + wall] = True
    for i, j in zip(*np.nonzero(down[:-1, :]), strict=True):
        occ[(i + 1) * pitch : (i + 1) * pitch + wall, j * pitch : (j + 1) * pitch + wall] = True
    return occ


def make_open(width: int, height: int, discs: int = 40, seed: int = 1) -> BoolGrid:
    """Occupancy of an open room: 3-cell border and ``discs`` round pillars."""
    rng = np.random.default_rng(seed)
    occ = np.zeros((height, width), dtype=np.uint8)
    occ[:3], occ[-3:], occ[:, :3], occ[:, -3:] = 1, 1, 1, 1
    for _ in range(discs):
        centre = (int(rng.integers(20, width - 20)), int(rng.integers(20, height - 20)))
        cv2.circle(occ, centre, int(rng.integers(3, 12)), 1, thickness=-1)
    return occ.astype(bool)


def known_belief(occ: BoolGrid) -> BeliefGrid:
    """Fully known belief grid of an occupancy grid."""
    return np.where(occ, OCCUPIED, FREE).astype(np.uint8)


def partial_belief(occ: BoolGrid, fraction: float = 0.35, seeds: int = 10) -> BeliefGrid:
    """Belief that knows the ``fraction`` of cells nearest to a few seed points."""
    rng = np.random.default_rng(2)
    rows, cols = occ.shape
    far = np.ones(occ.shape, dtype=np.uint8)
    far[rng.integers(0, rows, seeds), rng.integers(0, cols, seeds)] = 0
    dist = cv2.distanceTransform(far, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
    belief = known_belief(occ)
    belief[dist > np.quantile(dist, fraction)] = UNKNOWN
    return belief


def median_ms(fn: Callable[[], object]) -> float:
    """Median wall time of ``REPEATS`` calls, in ms."""
    times = []
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return 1e3 * statistics.median(times)


def corners(passable: BoolGrid) -> tuple[tuple[float, float], tuple[int, int]]:
    """World point of the passable cell nearest the top-left corner, cell of the far one."""
    rows, cols = np.nonzero(passable)
    first, last = np.argmin(rows + cols), np.argmax(rows + cols)
    return (cols[first] + 0.5, rows[first] + 0.5), (int(rows[last]), int(cols[last]))


def bench_map(name: str, occ: BoolGrid, *, mcp: bool) -> None:
    """Print the kernel medians for one map."""
    belief = known_belief(occ)
    passable = traversable(belief, CLEARANCE)
    start, (goal_r, goal_c) = corners(passable)
    goal_xy = (goal_c + 0.5, goal_r + 0.5)
    near_xy = (start[0] + 30.0, start[1] + 12.0)
    field = distance_field(passable, start)
    partial = partial_belief(occ)
    p_passable = traversable(partial, CLEARANCE)
    p_start, _ = corners(p_passable)
    p_field = distance_field(p_passable, p_start)
    frontiers = find_frontiers(partial)
    kernels: list[tuple[str, Callable[[], object]]] = [
        ("traversable (fully known)", lambda: traversable(belief, CLEARANCE)),
        ("distance_field from a corner (fully known)", lambda: distance_field(passable, start)),
        ("distance_field limit 150", lambda: distance_field(passable, start, limit=150.0)),
        ("path_to the far corner", lambda: field.path_to(goal_r, goal_c)),
        ("plan_path corner to corner", lambda: plan_path(passable, start, goal_xy)),
        ("plan_path to a cell ~32 away", lambda: plan_path(passable, start, near_xy)),
    ]  # fmt: skip
    if mcp:
        costs = np.where(passable, 1.0, np.inf)
        start_rc = (int(start[1]), int(start[0]))
        kernels.append((
            "  (skimage MCP_Geometric all cells, for comparison)",
            lambda: MCP_Geometric(costs, fully_connected=True).find_costs([start_rc]),
        ))  # fmt: skip
    kernels += [
        ("traversable (35% known)", lambda: traversable(partial, CLEARANCE)),
        ("distance_field (35% known)", lambda: distance_field(p_passable, p_start)),
        ("find_frontiers (35% known)", lambda: find_frontiers(partial)),
    ]
    for reach in (4.2, 15.0):
        kernels.append((
            f"frontier_targets reach {reach:g}",
            lambda r=reach: frontier_targets(frontiers, p_field, p_passable, r),
        ))  # fmt: skip
    cost = float(field.cost_at(np.array([goal_r]), np.array([goal_c]))[0])
    print(f"\n{name} {occ.shape[1]}x{occ.shape[0]}: {passable.mean():.0%} passable, "
          f"corner-to-corner cost {cost:.1f}; 35% known: {len(frontiers)} clusters "
          f"(>= 3 cells), {len(frontiers.cells_rc)} frontier cells")  # fmt: skip
    for label, fn in kernels:
        print(f"  {label:<52} {median_ms(fn):9.2f} ms")


def first_search_ms() -> float:
    """Wall time of this process's first ``distance_field`` call (JIT compile or cache load)."""
    t0 = time.perf_counter()
    distance_field(np.ones((3, 3), dtype=bool), (1.5, 1.5))
    return 1e3 * (time.perf_counter() - t0)


def main() -> None:
    """Run the benchmark on every map."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--skip-big", action="store_true", help="skip the 2000x2000 maze")
    args = parser.parse_args()
    print(f"first search in this process (numba compile or cache load): {first_search_ms():.0f} ms")
    print(f"median of {REPEATS} runs, clearance {CLEARANCE}, cv2 threads {cv2.getNumThreads()}")
    bench_map("maze800", make_maze(800, 600, pitch=25, wall=3), mcp=True)
    bench_map("open800", make_open(800, 600), mcp=True)
    if not args.skip_big:
        bench_map("maze2000", make_maze(2000, 2000, pitch=40, wall=4), mcp=False)


if __name__ == "__main__":
    main()
