"""Procedural maps (phase 0, input data): caves and open rubble sites.

* **cave**: a cellular automaton on a grid ``scale`` times coarser than the map: each cell
  rock with chance ``fill``, then ``smooth`` rounds in which a cell with 5 or more rock
  cells among its 3 x 3 block becomes rock and any other cell open; scaled up to the map,
  its largest open space kept (the rest filled). A cave whose space covers less than
  ``min_open`` of the map is drawn again from the same stream (at most 50 times).
* **rubble**: an open site inside an outer wall, with ``fragments`` standing wall pieces
  and rubble pieces (discs and rotated boxes up to ``piece_max`` cells) until ``density``
  of the site is covered; its largest open space kept.
"""

from __future__ import annotations

import cv2
import numpy as np
from scipy import ndimage

from mresim_phys.mapgen.params import CaveParams, RubbleParams
from mresim_phys.types import BoolGrid

ATTEMPTS = 50  # caves drawn before giving up on min_open
FOUR = ndimage.generate_binary_structure(2, 1)


def cave(p: CaveParams, width: int, height: int, rng: np.random.Generator) -> BoolGrid:
    """A cave (module docstring); ValueError naming ``min_open`` if none is open enough."""
    for _ in range(ATTEMPTS):
        occupied = keep_largest(rock(p, width, height, rng))
        if np.count_nonzero(~occupied) >= p.min_open * occupied.size:
            return occupied
    raise ValueError(
        f"min_open: no cave of fill {p.fill} drawn from this seed left {p.min_open:.0%} of the"
        " map open; give a lower fill, more smooth rounds or a lower min_open"
    )


def rock(p: CaveParams, width: int, height: int, rng: np.random.Generator) -> BoolGrid:
    """One draw of the automaton, scaled up to the map, with its outer wall."""
    rows, cols = -(-height // p.scale), -(-width // p.scale)
    coarse = rng.random((rows, cols)) < p.fill
    for _ in range(p.smooth):
        padded = np.pad(coarse, 1, constant_values=True).astype(np.float64)
        counts = ndimage.uniform_filter(padded, 3, mode="constant") * 9
        coarse = np.rint(counts[1:-1, 1:-1]).astype(np.int32) >= 5
    fine = np.kron(coarse, np.ones((p.scale, p.scale), dtype=bool))[:height, :width]
    return border(fine, p.wall)


def rubble(p: RubbleParams, width: int, height: int, rng: np.random.Generator) -> BoolGrid:
    """A rubble site (module docstring)."""
    site = np.zeros((height, width), dtype=np.uint8)
    for _ in range(p.fragments):
        length = int(rng.integers(max(4, p.fragment_max // 4), p.fragment_max + 1))
        x, y = int(rng.integers(0, width)), int(rng.integers(0, height))
        angle = float(rng.choice([0.0, 0.5, 0.25, 0.75]) * np.pi + rng.normal(0.0, 0.05))
        end = (int(x + length * np.cos(angle)), int(y + length * np.sin(angle)))
        cv2.line(site, (x, y), end, 1, thickness=p.wall)
    target = p.density * width * height
    while np.count_nonzero(site) < target:
        x, y = int(rng.integers(0, width)), int(rng.integers(0, height))
        size = int(rng.integers(1, p.piece_max + 1))
        if rng.random() < 0.5:
            cv2.circle(site, (x, y), max(1, size // 2), 1, thickness=-1)
        else:
            box = (
                (float(x), float(y)),
                (float(size), float(max(1, size // 2))),
                float(rng.uniform(0, 180)),
            )
            cv2.fillPoly(site, [np.intp(cv2.boxPoints(box))], 1)
    return keep_largest(border(site.astype(bool), p.wall))


def border(occupied: BoolGrid, wall: int) -> BoolGrid:
    """``occupied`` with an outer wall ``wall`` cells thick."""
    out: BoolGrid = occupied.copy()
    out[:wall, :] = out[-wall:, :] = True
    out[:, :wall] = out[:, -wall:] = True
    return out


def keep_largest(occupied: BoolGrid) -> BoolGrid:
    """``occupied`` with every open space but the largest (4-connected) filled."""
    labels, count = ndimage.label(~occupied, structure=FOUR)
    if count <= 1:
        return occupied
    sizes = np.bincount(labels.ravel())
    sizes[0] = 0
    out: BoolGrid = labels != int(np.argmax(sizes))
    return out
