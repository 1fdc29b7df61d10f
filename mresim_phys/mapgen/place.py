"""Procedural maps (phase 0, input data): where the base and the robots start.

The places a body of ``radius`` may stand on are the open cells at least ``radius + 1``
cells (centre to centre) from every wall; the base and the starts lie in the largest
4-connected set of them, so every robot can drive to every other and to the base. The base
stands at the place nearest to one of the map's corners (drawn from the stream: the
entrance of the building); the starts are the places nearest to the base, at least
``2 * radius + 1`` cells from it and from each other.
"""

from __future__ import annotations

import cv2
import numpy as np
from scipy import ndimage

from mresim_phys.types import BoolGrid

Point = tuple[float, float]
FOUR = ndimage.generate_binary_structure(2, 1)


def places(occupied: BoolGrid, radius: float) -> BoolGrid:
    """The largest 4-connected set of cells a body of ``radius`` may stand on."""
    free = (~occupied).astype(np.uint8)
    clearance = cv2.distanceTransform(free, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
    fits = clearance >= radius + 1.0
    labels, count = ndimage.label(fits, structure=FOUR)
    if count == 0:
        return np.zeros_like(occupied)
    sizes = np.bincount(labels.ravel())
    sizes[0] = 0
    out: BoolGrid = labels == int(np.argmax(sizes))
    return out


def base_and_starts(
    occupied: BoolGrid, radius: float, robots: int, rng: np.random.Generator
) -> tuple[Point, list[Point]]:
    """The base and ``robots`` starts (module docstring), as cell centres (x, y).

    Raises:
        ValueError: naming ``robots`` or ``radius`` when the map has no room for them.
    """
    room = places(occupied, radius)
    rows, cols = np.nonzero(room)
    if len(rows) == 0:
        raise ValueError(f"radius: no open space on this map fits a body of radius {radius}")
    corner_r, corner_c = [(0, 0), (0, 1), (1, 0), (1, 1)][int(rng.integers(4))]
    corner = (corner_r * (occupied.shape[0] - 1), corner_c * (occupied.shape[1] - 1))
    first = int(np.argmin((rows - corner[0]) ** 2 + (cols - corner[1]) ** 2))
    base = (int(rows[first]), int(cols[first]))
    order = np.argsort((rows - base[0]) ** 2 + (cols - base[1]) ** 2, kind="stable")
    spacing = (2 * radius + 1) ** 2
    chosen: list[tuple[int, int]] = [base]
    for k in order.tolist():
        cell = (int(rows[k]), int(cols[k]))
        if all((cell[0] - r) ** 2 + (cell[1] - c) ** 2 >= spacing for r, c in chosen):
            chosen.append(cell)
            if len(chosen) == robots + 1:
                break
    if len(chosen) < robots + 1:
        raise ValueError(
            f"robots: the open space holds {len(chosen) - 1} starts {2 * radius + 1:g} cells"
            f" apart, not {robots}; give fewer robots or a smaller radius"
        )
    centre = [(c + 0.5, r + 0.5) for r, c in chosen]
    return centre[0], centre[1:]
