"""Which aisles of the original MRESim's maps our robots enter, measured (a script).

For every map of ``tools/compare_original.py``'s cases (and the library), the free pixels
8-connected to the base pixel under the original's wall rule (only pure black is wall:
where the original's pixel robots can go), and the share of them within 2 cells of a cell
our robot's centre can reach from the base: planning at clearance ``radius + wall_margin``
= 1.0 and with the body alone (radius 0.5, the relaxed clearance of
``strategies/relax.py``). Prints the Markdown table of docs/differences-from-original.md::

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

from mresim_phys.world.explorable import positions  # noqa: E402

CLEARANCES = (1.0, 0.5)  # planner (radius 0.5 + margin 0.5), body alone
LOOK = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (5, 5))  # within 2 cells
HEADER = (
    "| map | free pixels a pixel robot reaches | planner, clearance 1.0 | body only, radius 0.5 |"
    "\n|---|---|---|---|"
)
EXTRA = ("environments/library.png=config/8robots_library",)


def component(mask: np.ndarray, seed: tuple[int, int]) -> np.ndarray:
    """The 8-connected component of ``mask`` holding ``seed`` (or the mask cell nearest it)."""
    _, labels = cv2.connectedComponents(mask.astype(np.uint8), connectivity=8)
    r, c = seed
    if not mask[r, c]:
        rows, cols = np.nonzero(mask)
        k = int(np.argmin((rows - r) ** 2 + (cols - c) ** 2))
        r, c = int(rows[k]), int(cols[k])
    return np.asarray(labels == labels[r, c])


def shares(occupied: np.ndarray, seed: tuple[int, int]) -> tuple[int, list[float]]:
    """Free pixels a pixel robot reaches, and the share of them near our robot's reach."""
    pixels = component(~occupied, seed)
    out = []
    for clearance in CLEARANCES:
        reach = component(positions(occupied, clearance), seed).astype(np.uint8)
        near = cv2.dilate(reach, LOOK).astype(bool)
        out.append(float(np.count_nonzero(near & pixels)) / float(np.count_nonzero(pixels)))
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
            count, values = shares(original_obstacles(case.map_path), (int(y), int(x)))
            cells = " | ".join(f"{v:.4f}" for v in values)
            print(f"| {case.key} | {count:,} | {cells} |")
    except CompareError as exc:
        print(f"original_aisles: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(HERE.parent))
    sys.exit(main())
