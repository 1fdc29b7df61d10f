"""Benchmark of the whole step against map size: the library at 800x600 and at 2000x2000.

The speed issue's bar: a 2000x2000 map at the same team and settings costs at most 3x
the 800x600 one per step (nothing in a step may scan the whole grid at every call).
The large map is built here, not shipped: the library floor (``mresim_phys/data/
library.png``) tiled 3 x 4 (cropped to 2000x2000), with a 24-cell doorway cut through
every wall between neighbouring tiles so the team can spread over the whole building.
Both maps run the ``original`` preset (speed 10, laser 200, comm 200, radius 0.5) with
the same team from the same start; each round times both maps in turn (interleaved),
and the script prints the median over rounds of each map's median ms per step, and the
ratio.

Run from the repository root: ``python benchmarks/bench_scale.py [--robots 8] [--rounds 3]``.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
from pathlib import Path

import cv2
import numpy as np

from mresim_phys.output.bench import PRESETS, time_team

TILE_ROWS, TILE_COLS = 600, 800
SIDE = 2000
DOOR = 24  # cells: width of a doorway between neighbouring tiles


def large_library(path: Path) -> Path:
    """Write the 2000x2000 tiled library to ``path`` and return it."""
    tile = cv2.imread(str(PRESETS["original"].map_path), cv2.IMREAD_GRAYSCALE)
    if tile is None:
        raise SystemExit(f"cannot read {PRESETS['original'].map_path}")
    reps = (-(-SIDE // TILE_ROWS), -(-SIDE // TILE_COLS))
    image = np.tile(tile, reps)[:SIDE, :SIDE].copy()
    for row in range(TILE_ROWS, SIDE, TILE_ROWS):  # doorways through horizontal seams
        for col in range(TILE_COLS // 2, SIDE, TILE_COLS):
            image[row - 12 : row + 12, col - DOOR // 2 : col + DOOR // 2] = 255
    for col in range(TILE_COLS, SIDE, TILE_COLS):  # ... and vertical seams
        for row in range(TILE_ROWS // 2, SIDE, TILE_ROWS):
            image[row - DOOR // 2 : row + DOOR // 2, col - 12 : col + 12] = 255
    cv2.imwrite(str(path), image)
    return path


def main() -> None:
    """Time both maps in interleaved rounds and print medians and the ratio."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", type=int, default=8)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--steps", type=int, default=100)
    args = parser.parse_args()
    preset = PRESETS["original"]
    with tempfile.TemporaryDirectory() as tmp:
        maps = {"800x600": preset.map_path, "2000x2000": large_library(Path(tmp) / "big.png")}
        medians: dict[str, list[float]] = {name: [] for name in maps}
        for _ in range(args.rounds):
            for name, path in maps.items():
                result = time_team(args.robots, path, preset.warmup, args.steps, preset)[0]
                medians[name].append(result.median_ms)
    small, large = (statistics.median(medians[name]) for name in maps)
    print(f"library, {args.robots} robots, original settings, {args.rounds} rounds:")
    for name, values in medians.items():
        rounds = " / ".join(f"{v:.2f}" for v in values)
        print(f"  {name:>9}: median {statistics.median(values):6.2f} ms per step ({rounds})")
    print(f"  2000x2000 / 800x600 = {large / small:.2f} (bar: <= 3)")


if __name__ == "__main__":
    main()
