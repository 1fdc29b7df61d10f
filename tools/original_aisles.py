"""Which aisles of the original MRESim's maps our robots enter, measured (a script).

For every map of ``tools/compare_original.py``'s cases (and the library), the free pixels
8-connected to the base pixel under the original's wall rule (only pure black is wall:
where the original's pixel robots can go), and the share of them within 2 cells of a cell
our robot's centre can reach from the base (4-connected positions, the explorable area's
rule: a diagonal pinch between two wall pixels that touch at a corner lets a pixel robot
through, not ours): planning at clearance ``radius + wall_margin`` = 1.0 and with the body
alone (radius 0.5, the relaxed clearance of ``strategies/relax.py``). Prints the Markdown
table of docs/differences-from-original.md::

    python tools/original_aisles.py --original /work/orig
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import cv2
import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from compare_original import DEFAULT_CASES, case_of  # noqa: E402
from original_metrics import CompareError, base_pixel, original_obstacles  # noqa: E402

from mresim_phys.world.explorable import positions, start_seeds  # noqa: E402
from mresim_phys.world.maps import connected_to  # noqa: E402

CLEARANCES = (1.0, 0.5)  # planner (radius 0.5 + margin 0.5), body alone
LOOK = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (5, 5))  # within 2 cells
HEADER = (
    "| map | free pixels a pixel robot reaches | planner, clearance 1.0 | body only, radius 0.5 |"
    "\n|---|---|---|---|"
)
EXTRA = ("environments/library.png=config/8robots_library",)


def pixel_reach(occupied: np.ndarray, seed: tuple[int, int]) -> np.ndarray:
    """The free pixels 8-connected to ``seed`` (row, col): where the original's robots go.
    CompareError when ``seed`` is off the map or a wall pixel (no robot starts there)."""
    (r, c), (rows, cols) = seed, occupied.shape
    inside = 0 <= r < rows and 0 <= c < cols
    if not inside or occupied[r, c]:
        where = "a wall pixel" if inside else "off the map"
        raise CompareError(f"the base pixel (x {c}, y {r}) is {where}")
    _, labels = cv2.connectedComponents((~occupied).astype(np.uint8), connectivity=8)
    return np.asarray(labels == labels[seed])


def body_reach(occupied: np.ndarray, seed: tuple[int, int], clearance: float) -> np.ndarray:
    """The positions of a body of radius ``clearance`` it reaches from the pixel ``seed``
    (the explorable area's rule: ``world.explorable.start_seeds``, 4-connected)."""
    places = positions(occupied, clearance)
    seeds = start_seeds(occupied, places, (seed[1] + 0.5, seed[0] + 0.5))
    return connected_to(places, np.array(seeds, dtype=np.intp).reshape(-1, 2))


def shares(occupied: np.ndarray, seed: tuple[int, int]) -> tuple[int, list[float]]:
    """Free pixels a pixel robot reaches, and the share of them near our robot's reach."""
    pixels = pixel_reach(occupied, seed)
    out = []
    for clearance in CLEARANCES:
        near = cv2.dilate(body_reach(occupied, seed, clearance).astype(np.uint8), LOOK)
        reached = np.count_nonzero(near.astype(bool) & pixels)
        out.append(float(reached) / float(np.count_nonzero(pixels)))
    return int(np.count_nonzero(pixels)), out


def main(argv: list[str] | None = None) -> int:
    """Print one table row per map."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--original", type=Path, required=True, help="the original's tree")
    args = parser.parse_args(argv)
    print(HEADER)
    try:
        for spec in (*DEFAULT_CASES, *EXTRA):
            case = case_of(spec, args.original)
            x, y = base_pixel(case.team_path)
            try:
                count, values = shares(original_obstacles(case.map_path), (int(y), int(x)))
            except CompareError as exc:
                raise CompareError(f"{case.team_path}: {exc}") from None
            cells = " | ".join(f"{v:.4f}" for v in values)
            print(f"| {case.key} | {count:,} | {cells} |")
    except CompareError as exc:
        print(f"original_aisles: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(HERE.parent))
    sys.exit(main())
