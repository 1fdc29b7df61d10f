"""World (phase 1, geometry) benchmark: what a change of the world costs next to building one.

Run ``python benchmarks/bench_world.py`` from the repository root. On ``maps/office.png``
(800 x 600) it prints the median milliseconds of: building the World (segments, Space,
4 robot bodies); ``set_cells`` on a 10 x 10 box in open space and on one across a wall
(each sample closes or reopens the box); moving a 3 x 3 movable obstacle by one cell;
the reachable set after such a change, labelled again over the whole map
(``free_components_mask``) or followed locally (``Reachable.follow``); retargeting the
coverage counter over the whole map or over the changed window; and a 181-ray scan in
a freshly built world and in one that has been through thousands of changes (the Space's
tree must not degrade). Samples of every case are interleaved, so a busy machine slows
them alike. This is a script, not a test.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
from scipy import ndimage

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from mresim_phys.knowledge.coverage import Coverage  # noqa: E402
from mresim_phys.scenario.readers import load_map  # noqa: E402
from mresim_phys.types import BoolGrid  # noqa: E402
from mresim_phys.world.changes import Change  # noqa: E402
from mresim_phys.world.maps import free_components_mask  # noqa: E402
from mresim_phys.world.reach import MARGIN, Reachable  # noqa: E402
from mresim_phys.world.space import World  # noqa: E402

RADII = [2.0, 2.0, 1.5, 1.5]
START = (40.0, 300.0)
Case = Callable[[], object]


def open_box(occupied: BoolGrid, size: int = 10) -> tuple[int, int, int, int]:
    """A ``size`` x ``size`` box of free cells with free space around it, mid-map."""
    clear = ndimage.minimum_filter(~occupied, size=size + 8)
    rows, cols = np.nonzero(clear)
    k = len(rows) // 2
    row, col = int(rows[k]) - size // 2, int(cols[k]) - size // 2
    return row, row + size, col, col + size


def wall_box(occupied: BoolGrid, size: int = 10) -> tuple[int, int, int, int]:
    """A ``size`` x ``size`` box straddling a wall (some cells occupied, most free)."""
    share = ndimage.uniform_filter(occupied.astype(float), size=size)
    rows, cols = np.nonzero((share > 0.15) & (share < 0.4))
    k = len(rows) // 2
    row, col = int(rows[k]) - size // 2, int(cols[k]) - size // 2
    return row, row + size, col, col + size


def toggler(world: World, box: tuple[int, int, int, int]) -> Case:
    """Each call closes the box (all walls), the next restores what was there."""
    row0, row1, col0, col1 = box
    original = world.occupied[row0:row1, col0:col1].copy()
    state = {"closed": False}

    def run() -> Change:
        state["closed"] = not state["closed"]
        return world.set_cells(box, True if state["closed"] else original)

    return run


def cart(world: World, box: tuple[int, int, int, int]) -> Case:
    """Each call moves a 3 x 3 movable obstacle one cell right, then back."""
    row, col = box[0] + 3, box[2] + 3
    world.add_movable("cart", (3, 3), (row, col))
    state = {"right": False}

    def run() -> Change:
        state["right"] = not state["right"]
        return world.move_movable("cart", (row, col + state["right"]))

    return run


def scan_case(world: World, occupied: BoolGrid, seed: int = 0) -> Case:
    """A 181-ray, 180-degree scan of range 100 from one of 50 free poses per call."""
    rng = np.random.default_rng(seed)
    free = np.argwhere(~occupied)
    poses = free[rng.choice(len(free), 50, replace=False)][:, ::-1] + 0.5
    offsets = np.linspace(-np.pi / 2, np.pi / 2, 181)
    walls = world.query_filter(None, robots_block=False)
    counter = iter(range(10**9))

    def run() -> object:
        x, y = poses[next(counter) % len(poses)]
        return world.cast_rays((x, y), offsets + rng.uniform(-np.pi, np.pi), 100.0, walls)

    return run


def churn(world: World, occupied: BoolGrid, changes: int, seed: int = 1) -> None:
    """Put ``world`` through ``changes`` random small changes that cancel out in pairs."""
    rng = np.random.default_rng(seed)
    rows, cols = occupied.shape
    for _ in range(changes // 2):
        row, col = int(rng.integers(0, rows - 6)), int(rng.integers(0, cols - 6))
        box = (row, row + 5, col, col + 5)
        before = world.occupied[row : row + 5, col : col + 5].copy()
        world.set_cells(box, ~before)
        world.set_cells(box, before)


def cases(occupied: BoolGrid, churned: int) -> dict[str, Case | Prepared]:
    """Every timed case, by name (each call is one sample)."""
    box, across = open_box(occupied), wall_box(occupied)
    world = World(occupied.copy(), RADII)
    reach = Reachable(world.occupied, [START])
    coverage = Coverage(reach.mask)
    close = toggler(world, box)
    old_world = World(occupied.copy(), RADII)
    churn(old_world, occupied, churned)
    return {
        "build World": lambda: World(occupied.copy(), RADII),
        "set_cells 10x10 open": toggler(World(occupied.copy(), RADII), box),
        "set_cells 10x10 across wall": toggler(World(occupied.copy(), RADII), across),
        "move 3x3 movable 1 cell": cart(World(occupied.copy(), RADII), box),
        "reachable: full labelling": lambda: free_components_mask(world.occupied, [START]),
        "reachable: follow 10x10 change": Prepared(
            close, lambda c: reach.follow(world.occupied, [c])
        ),
        "retarget coverage: whole map": lambda: coverage.retarget(reach.mask),
        "retarget coverage: 14x14 window": lambda: coverage.retarget(reach.mask, grown(box)),
        "scan 181 rays, fresh world": scan_case(World(occupied.copy(), RADII), occupied),
        f"scan 181 rays, after {churned} changes": scan_case(old_world, occupied),
    }


def grown(box: tuple[int, int, int, int]) -> tuple[int, int, int, int]:
    """The window ``Reachable.follow`` relabels around a change of ``box``."""
    return box[0] - MARGIN, box[1] + MARGIN, box[2] - MARGIN, box[3] + MARGIN


class Prepared:
    """A case whose sample times ``run(prepare())``, not ``prepare()``."""

    def __init__(self, prepare: Callable[[], Change], run: Callable[[Change], object]) -> None:
        self.prepare, self.run = prepare, run


def interleaved_medians(named: dict[str, Case | Prepared], repeats: int) -> dict[str, float]:
    """Median ms of each case, its samples interleaved with every other case's."""
    samples: dict[str, list[float]] = {name: [] for name in named}
    for _ in range(repeats):
        for name, case in named.items():
            if isinstance(case, Prepared):
                change = case.prepare()
                start = time.perf_counter()
                case.run(change)
            else:
                start = time.perf_counter()
                case()
            samples[name].append(1e3 * (time.perf_counter() - start))
    return {name: statistics.median(times) for name, times in samples.items()}


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark and print the medians."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=41, help="samples per case (odd)")
    parser.add_argument("--churn", type=int, default=4000, help="changes before the old scan")
    args = parser.parse_args(argv)
    occupied = load_map(ROOT / "maps" / "office.png").occupied
    named = cases(occupied, args.churn)
    interleaved_medians(named, 3)  # warm up (first changes build the layers)
    medians = interleaved_medians(named, args.repeats)
    build = medians["build World"]
    print(f"office.png {occupied.shape[1]}x{occupied.shape[0]}, medians of {args.repeats}")
    width = max(map(len, medians))
    for name, ms in medians.items():
        ratio = "" if name == "build World" else f"  {build / ms:7.1f}x cheaper than building"
        print(f"{name:<{width}}  {ms:8.3f} ms{ratio}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
