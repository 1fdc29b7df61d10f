"""Path smoothing (phase 4b): line-of-sight shortcuts over a grid path.

Robots move in continuous space, so a cell-centre path can be shortened: from each kept
point, the path jumps to the farthest later point in line of sight, and keeps that one.
Line of sight is checked against the robot's own configuration-space mask: every cell the
segment passes through (its supercover, computed exactly in integers) must be passable,
and where the segment crosses a cell corner exactly, one of the two cells beside that
corner must be passable too (the grid's own corner rule). Every point of a kept segment
then lies in a passable cell, within sqrt(2)/2 of a passable centre, the same guarantee as
a grid move: with a clearance of at least radius + 0.71 the robot never touches a known
obstacle, and it never enters an unknown cell.

Typical use: ``smooth_path(path, passable)`` on a path from any grid planner.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

from mresim_phys.types import BoolGrid, FloatArray


@njit(cache=True, nogil=True)
def line_of_sight(passable: NDArray[np.bool_], r0: int, c0: int, r1: int, c1: int) -> bool:
    """Whether the segment between the centres of two cells stays in passable cells.

    Walks the supercover of the segment: at each step the next cell boundary crossed is
    the nearer of the next vertical and horizontal one, compared exactly as
    ``(1 + 2 ix) * ny`` against ``(1 + 2 iy) * nx``.

    >>> grid = np.ones((3, 3), dtype=bool)
    >>> line_of_sight(grid, 0, 0, 2, 2)
    True
    >>> grid[0, 1] = grid[1, 0] = grid[1, 1] = False
    >>> line_of_sight(grid, 0, 0, 2, 2)
    False
    """
    nx, ny = abs(c1 - c0), abs(r1 - r0)
    sx = 1 if c1 > c0 else -1
    sy = 1 if r1 > r0 else -1
    r, c, ix, iy = r0, c0, 0, 0
    if not passable[r, c]:
        return False
    while ix < nx or iy < ny:
        d = (1 + 2 * ix) * ny - (1 + 2 * iy) * nx
        if d == 0:  # through a corner: one of the two cells beside it must be passable
            if not (passable[r + sy, c] or passable[r, c + sx]):
                return False
            r, c, ix, iy = r + sy, c + sx, ix + 1, iy + 1
        elif d < 0:
            c, ix = c + sx, ix + 1
        else:
            r, iy = r + sy, iy + 1
        if not passable[r, c]:
            return False
    return True


@njit(cache=True, nogil=True)
def _shortcut(
    passable: NDArray[np.bool_], rows: NDArray[np.int64], cols: NDArray[np.int64]
) -> NDArray[np.int64]:
    """Indices of the points kept by greedy farthest-visible shortcutting."""
    n = len(rows)
    keep = np.empty(n, dtype=np.int64)
    keep[0], count, anchor = 0, 1, 0
    for j in range(1, n - 1):
        if not line_of_sight(passable, rows[anchor], cols[anchor], rows[j + 1], cols[j + 1]):
            keep[count], count, anchor = j, count + 1, j
    keep[count] = n - 1
    return keep[: count + 1]


def smooth_path(path: FloatArray, passable: BoolGrid) -> FloatArray:
    """``path`` (cell centres, (n, 2) world x, y) with line-of-sight shortcuts taken.

    The first and last points stay; the kept points are a subsequence of ``path``, so the
    result is never longer. Paths of fewer than three points are returned unchanged.
    """
    if len(path) < 3:
        return path
    cols = np.floor(path[:, 0]).astype(np.int64)
    rows = np.floor(path[:, 1]).astype(np.int64)
    keep = _shortcut(np.ascontiguousarray(passable, dtype=np.bool_), rows, cols)
    return path[keep]
