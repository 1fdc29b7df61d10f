"""World (phase 1, geometry) benchmark: what the explorable area costs, built and followed.

Run ``python benchmarks/bench_explorable.py`` from the repository root. It prints the
median milliseconds of building :class:`~mresim_phys.world.explorable.Explorable` for one
robot (radius 0.5 and laser range 200; radius 1 and range 50; radius 2 and range 100, the
shipped scenarios' robot) on ``maps/office.png`` and ``maps/library.png`` (800 x 600) and
on a generated 2000 x 2000 building (:func:`building`: rooms on a 40-cell pitch whose
doors are 1 to 12 cells wide, so some let a robot see into a room it cannot enter), with
the explorable and 4-connected cell counts; then on the office, what following one change
costs: a 7-cell walker moving one cell along the corridor (local), and a room's door
closing or opening (the reachable positions regroup: computed afresh). This is a script,
not a test.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from mresim_phys.scenario.readers import load_map  # noqa: E402
from mresim_phys.types import BoolGrid, RobotSight  # noqa: E402
from mresim_phys.world.explorable import Explorable  # noqa: E402
from mresim_phys.world.maps import free_components_mask  # noqa: E402

ROBOTS = [(0.5, 200.0), (1.0, 50.0), (2.0, 100.0)]  # (radius, laser range)
MAPS = {"office": (40.5, 300.5), "library": (430.5, 520.5)}  # a start on each
PITCH, WALL = 40, 2  # generated building: room pitch and wall thickness (cells)


def building(size: int = 2000, seed: int = 1) -> BoolGrid:
    """A ``size`` x ``size`` grid of rooms: walls every :data:`PITCH` cells, one door of
    1-12 cells in each wall of each room, a pillar in one room of three."""
    rng = np.random.default_rng(seed)
    occupied = np.zeros((size, size), dtype=bool)
    occupied[:WALL], occupied[-WALL:], occupied[:, :WALL], occupied[:, -WALL:] = (True,) * 4
    for line in range(0, size, PITCH):
        occupied[line : line + WALL], occupied[:, line : line + WALL] = True, True
    for top in range(0, size - PITCH, PITCH):
        for left in range(0, size - PITCH, PITCH):
            for vertical in (False, True):
                width = int(rng.integers(1, 13))
                at = int(rng.integers(WALL + 2, PITCH - width - 2))
                if vertical:
                    occupied[top + at : top + at + width, left : left + WALL] = False
                else:
                    occupied[top : top + WALL, left + at : left + at + width] = False
            if rng.random() < 1 / 3:
                row, col = top + int(rng.integers(10, 28)), left + int(rng.integers(10, 28))
                occupied[row : row + 3, col : col + 3] = True
    return occupied


def median_ms(run: Callable[[], object], repeats: int) -> float:
    """Median wall time of ``repeats`` calls, in milliseconds."""
    times = []
    for _ in range(repeats):
        started = time.perf_counter()
        run()
        times.append(time.perf_counter() - started)
    return 1000 * statistics.median(times)


def bench_build(name: str, occupied: BoolGrid, start: tuple[float, float], repeats: int) -> None:
    """One line per robot kind: build time, explorable and 4-connected cells."""
    connected = int(free_components_mask(occupied, [start]).sum())
    for radius, sensor_range in ROBOTS:
        robots = [RobotSight(start, radius, sensor_range)]
        ms = median_ms(lambda robots=robots: Explorable(occupied, robots), repeats)
        cells = int(Explorable(occupied, robots).mask.sum())
        print(
            f"{name:9s} radius {radius:3.1f} range {sensor_range:5.0f}: {ms:7.1f} ms,"
            f" explorable {cells:,} of {connected:,} connected cells"
        )


def bench_changes(occupied: BoolGrid, steps: int) -> None:
    """A walker's moves and a door's closing on the office, ms per change."""
    truth = occupied.copy()
    ys, xs = np.mgrid[-3:4, -3:4]
    walker = xs**2 + ys**2 <= 9
    explorable = Explorable(truth, [RobotSight(MAPS["office"], 2.0, 100.0)] * 4)
    times = []
    for x in range(120, 120 + steps):
        box = (297, 304, x - 3, x + 5)
        before = truth[297:304, x - 3 : x + 5].copy()
        truth[297:304, x - 3 : x + 4] &= ~walker
        truth[297:304, x - 2 : x + 5] |= walker
        flips = before ^ truth[297:304, x - 3 : x + 5]
        started = time.perf_counter()
        explorable.update(truth, box, flips)
        times.append(time.perf_counter() - started)
    print(f"office walker move: {1000 * statistics.median(times):.2f} ms a change (median)")
    door = (277, 280, 371, 389)
    times = []
    for closed in (True, False) * 3:
        before = truth[277:280, 371:389].copy()
        truth[277:280, 371:389] = closed or occupied[277:280, 371:389]
        started = time.perf_counter()
        explorable.update(truth, door, before ^ truth[277:280, 371:389])
        times.append(time.perf_counter() - started)
    print(f"office door closes or opens: {1000 * statistics.median(times):.1f} ms a change")


def main(argv: list[str] | None = None) -> int:
    """Print the table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5, help="samples per case")
    args = parser.parse_args(argv)
    Explorable(np.zeros((20, 20), dtype=bool), [RobotSight((5.5, 5.5), 1.0, 5.0)])  # compile
    for name, start in MAPS.items():
        occupied = load_map(ROOT / "maps" / f"{name}.png").occupied
        bench_build(name, occupied, start, args.repeats)
    bench_build("generated", building(), (20.5, 20.5), max(args.repeats // 2, 1))
    bench_changes(load_map(ROOT / "maps" / "office.png").occupied, 60)
    return 0


if __name__ == "__main__":
    sys.exit(main())
