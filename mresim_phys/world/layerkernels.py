"""World (phase 1, kernels): compiled passes over the truth's layers for small changes.

A moving obstacle changes a few dozen cells a step; done with numpy, each change is
a dozen tiny array operations whose call overhead outweighs the work. These two
kernels do the same in one pass each (``world/changes.py`` calls them):

* :func:`footprint_clear`: whether a footprint at a place lies on the map, clear of
  other movables, of static walls (unless it may lie over them, as a door's ends do)
  and of robots' bodies;
* :func:`fold_truth`: fold a window of the static layer and the movable cover counts
  into the kinds, radio and truth grids, reporting which cells' truth flipped.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from mresim_phys.types import BoolGrid, FloatArray


@njit(cache=True, nogil=True, inline="always")
def _circle_overlaps_cell(x: float, y: float, radius: float, row: int, col: int) -> bool:
    """Whether a circle overlaps (not just touches) cell (row, col)."""
    dx = max(col - x, 0.0, x - (col + 1))
    dy = max(row - y, 0.0, y - (row + 1))
    return dx * dx + dy * dy < radius * radius


@njit(cache=True, nogil=True)
def footprint_clear(
    cover: np.ndarray,
    static: BoolGrid,
    footprint: BoolGrid,
    row: int,
    col: int,
    own: BoolGrid,
    own_row: int,
    own_col: int,
    over_walls: bool,
    circles: FloatArray,
) -> bool:
    """Whether ``footprint`` with its top-left cell at (row, col) lies on the map and
    covers no cell covered by another movable (``own``, the moving one's footprint at
    (own_row, own_col), does not count; an empty ``own`` for a new one), no static
    wall unless ``over_walls``, and no robot body (``circles``: rows x, y, radius)."""
    rows, cols = static.shape
    h, w = footprint.shape
    if row < 0 or col < 0 or row + h > rows or col + w > cols:
        return False
    oh, ow = own.shape
    for i in range(h):
        for j in range(w):
            if not footprint[i, j]:
                continue
            r, c = row + i, col + j
            if static[r, c] and not over_walls:
                return False
            others = int(cover[r, c])
            a, b = r - own_row, c - own_col
            if 0 <= a < oh and 0 <= b < ow and own[a, b]:
                others -= 1
            if others > 0:
                return False
            for k in range(len(circles)):
                if _circle_overlaps_cell(circles[k, 0], circles[k, 1], circles[k, 2], r, c):
                    return False
    return True


@njit(cache=True, nogil=True)
def fold_truth(
    static: BoolGrid,
    cover: np.ndarray,
    quiet: np.ndarray,
    radio: BoolGrid,
    kinds: np.ndarray,
    occupied: BoolGrid,
    flipped: BoolGrid,
    row0: int,
    row1: int,
    col0: int,
    col1: int,
) -> tuple[int, int, int, int, int, int, int, int]:
    """Fold the window (row0:row1, col0:col1) of the layers into the grids, in place.

    ``kinds`` (padded: cell (r, c) at [r + 1, c + 1]) takes the static layer, ``radio``
    (unless it is empty) the static layer and the radio-blocking cover, ``occupied``
    the static layer and all cover. ``flipped`` (the window's shape) receives where
    ``occupied`` changed. Returns the bounding boxes (row0, row1, col0, col1) of the
    cells whose kind changed and of the flipped cells; an empty box is all -1.
    """
    kind_box = np.array([row1, -1, col1, -1])
    flip_box = np.array([row1, -1, col1, -1])
    has_radio = radio.shape[0] > 0
    for r in range(row0, row1):
        for c in range(col0, col1):
            wall = static[r, c]
            if has_radio:
                radio[r, c] = wall or cover[r, c] > quiet[r, c]
            if kinds[r + 1, c + 1] != wall:
                kinds[r + 1, c + 1] = wall
                _grow(kind_box, r, c)
            truth = wall or cover[r, c] > 0
            flip = truth != occupied[r, c]
            flipped[r - row0, c - col0] = flip
            if flip:
                occupied[r, c] = truth
                _grow(flip_box, r, c)
    k0, k1, k2, k3 = _closed(kind_box)
    f0, f1, f2, f3 = _closed(flip_box)
    return k0, k1, k2, k3, f0, f1, f2, f3


@njit(cache=True, nogil=True, inline="always")
def _grow(box: np.ndarray, r: int, c: int) -> None:
    box[0], box[1] = min(box[0], r), max(box[1], r)
    box[2], box[3] = min(box[2], c), max(box[3], c)


@njit(cache=True, nogil=True, inline="always")
def _closed(box: np.ndarray) -> tuple[int, int, int, int]:
    """A grown (min, max, min, max) box as half-open (row0, row1, col0, col1), or all -1."""
    if box[1] < 0:
        return -1, -1, -1, -1
    return box[0], box[1] + 1, box[2], box[3] + 1
