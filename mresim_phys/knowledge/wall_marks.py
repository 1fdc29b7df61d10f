"""Wall marks (phase 3, mapping kernels): where a scan's rays mark walls, and which walls
they prove false.

The kernels ``knowledge.mapping.fold_scan`` calls for the edges of a scan's free polygon:

* :func:`hit_cell`: the wall cell a ray that ended on a wall hit (a ray grazing a wall
  corner marks the wall it touched, not the free cell diagonally beyond);
* :func:`mark_face`: two consecutive hits on one straight wall face, less than
  :data:`WALL_GAP` apart, mark the face between them (as the original joins close hits);
* :func:`chord_band`: the cells along a chord between two ray ends that lie past both
  flanking rays (a chord can cut across a wall corner) are trimmed from the fill;
* :func:`clear_contradicted`: a cell the map holds as wall that a ray of the scan went
  through is free (walls are solid, so that wall was false).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from mresim_phys.types import FREE, OCCUPIED, UNKNOWN, BeliefGrid, FloatArray, IntArray

WALL_GAP = 5.0  # cells: consecutive hits closer than this on one face are joined (original: 5 px)
NEAR_PARALLEL = 0.999  # cosine above which two face normals are the same face direction
NEAR_ROBOT = 1.0  # cells: the robot's own cell neighbourhood is free whatever the ray geometry
EDGE_BAND = 0.5 - 1e-6  # cells: chord band re-checked against the flanking rays (strict)
TRIMMED = 2  # mask value, inside the kernel only: a band cell excluded from the fill
THROUGH = 0.35  # cells: a ray this close to a cell's centre crossed its inside (0.7 cells)


@njit(cache=True, nogil=True)
def hit_cell(ex: float, ey: float, ux: float, uy: float, nx: float, ny: float) -> tuple[int, int]:
    """(row, col) of the wall cell a ray ending at (ex, ey) hit: across the surface
    (against its normal), on the ray's side of any other cell boundary through the end
    point. A ray that grazes a wall corner ends on two boundaries: the cell just past the
    end point along the ray is then the free one diagonally beyond the corner."""
    return math.floor(ey - 1e-3 * ny - 1e-6 * uy), math.floor(ex - 1e-3 * nx - 1e-6 * ux)


@njit(cache=True, nogil=True)
def clear_contradicted(
    ox: float,
    oy: float,
    angles: FloatArray,
    ranges: FloatArray,
    walls: IntArray,
    mask: BeliefGrid,
    belief: BeliefGrid,
    r0: int,
    c0: int,
) -> None:
    """Make FREE the OCCUPIED cells of ``walls`` (window indices, inside the polygon and
    not trimmed) that a ray of this scan went through: it passed within
    :data:`THROUGH` of the cell's centre (so through its inside, over 0.7 cells) and
    ended more than half a cell beyond it. Walls are solid, so such a cell is free now:
    an earlier bump, a wall face joined across a doorway or a person who has left. The
    rays checked are the few whose direction is nearest the cell's (evenly spread)."""
    n = len(angles)
    if n < 2:
        return
    step = (angles[n - 1] - angles[0]) / (n - 1)
    w = mask.shape[1]
    for i in range(len(walls)):
        r, c = walls[i] // w, walls[i] % w
        if mask[r, c] != 1:
            continue
        dx, dy = c + c0 + 0.5 - ox, r + r0 + 0.5 - oy
        turn = (math.atan2(dy, dx) - angles[0]) % (2.0 * math.pi)
        near = int(turn / step)
        for k in range(near - 1, near + 3):
            if 0 <= k < n:
                ux, uy = math.cos(angles[k]), math.sin(angles[k])
                along = dx * ux + dy * uy
                if abs(dx * uy - dy * ux) < THROUGH and along + 0.5 < ranges[k]:
                    belief[r + r0, c + c0] = FREE
                    break


@njit(cache=True, nogil=True)
def chord_band(
    ox: float,
    oy: float,
    ux: FloatArray,
    uy: FloatArray,
    ex: FloatArray,
    ey: FloatArray,
    ranges: FloatArray,
    chords: int,
    mask: BeliefGrid,
    r0: int,
    c0: int,
    skip_radial: bool = False,
) -> IntArray:
    """Mark TRIMMED the band cells of every chord that lie past both flanking rays.

    A chord joins the ends of rays k and k+1; its band cells are those whose
    centre lies within EDGE_BAND of it along its minor axis, between the two rays,
    farther from the robot than the nearer ray end (and than NEAR_ROBOT).
    With ``skip_radial``, a chord to a ray of length 0 (a beam-model ray left out:
    ``knowledge/evidence.py``) runs along its other ray, cuts no corner and is skipped.
    Returns their (row, col) in the window.
    """
    n = len(ex)
    h, w = mask.shape
    capacity = chords
    for k in range(chords):  # a chord has at most one band cell per major-axis step
        k1 = k + 1 if k + 1 < n else 0
        capacity += int(max(abs(ex[k1] - ex[k]), abs(ey[k1] - ey[k])))
    cells = np.empty((capacity + 1, 2), np.int64)
    count = 0
    for k in range(chords):
        k1 = k + 1 if k + 1 < n else 0
        if skip_radial and (ranges[k] <= 0.0 or ranges[k1] <= 0.0):
            continue
        ax, ay, bx, by = ex[k], ey[k], ex[k1], ey[k1]
        limit2 = max(min(ranges[k], ranges[k1]), NEAR_ROBOT) ** 2
        steep = abs(by - ay) > abs(bx - ax)
        if steep:  # walk rows, swap axes
            ax, ay, bx, by = ay, ax, by, bx
        if ax == bx:
            continue
        if ax > bx:
            ax, ay, bx, by = bx, by, ax, ay
        slope = (by - ay) / (bx - ax)
        lo, hi = (r0, r0 + h) if steep else (c0, c0 + w)
        for a in range(max(math.ceil(ax - 0.5), lo), min(math.floor(bx - 0.5) + 1, hi)):
            line = ay + (a + 0.5 - ax) * slope
            b = math.floor(line)  # the only centre that can be within 0.5 of the line
            if abs(b + 0.5 - line) >= EDGE_BAND:
                continue
            r, c = (a, b) if steep else (b, a)
            if not (r0 <= r < r0 + h and c0 <= c < c0 + w) or mask[r - r0, c - c0] != 0:
                continue
            px, py = c + 0.5 - ox, r + 0.5 - oy
            between = ux[k] * py - uy[k] * px >= 0.0 and px * uy[k1] - py * ux[k1] >= 0.0
            if between and px * px + py * py > limit2:
                mask[r - r0, c - c0] = TRIMMED
                cells[count, 0], cells[count, 1] = r - r0, c - c0
                count += 1
    return cells[:count]


@njit(cache=True, nogil=True)
def mark_face(
    belief: BeliefGrid,
    normals: FloatArray,
    ex: FloatArray,
    ey: FloatArray,
    ux: FloatArray,
    uy: FloatArray,
    k: int,
) -> None:
    """Mark OCCUPIED (where UNKNOWN) the run of cells joining hits k and k+1 on one face.

    Joined only if both normals agree, the face is a cell edge (axis-aligned), the
    hits lie on one line and are closer than WALL_GAP; the run lies half a cell
    inside the wall, along one row or one column.
    """
    nx, ny = normals[k, 0], normals[k, 1]
    gx, gy = ex[k + 1] - ex[k], ey[k + 1] - ey[k]
    if (
        nx * normals[k + 1, 0] + ny * normals[k + 1, 1] <= NEAR_PARALLEL
        or abs(nx * gx + ny * gy) >= 1e-6
        or gx * gx + gy * gy >= WALL_GAP * WALL_GAP
        or max(abs(nx), abs(ny)) <= NEAR_PARALLEL
    ):
        return
    ra, ca = hit_cell(ex[k], ey[k], ux[k], uy[k], nx, ny)
    rb, cb = hit_cell(ex[k + 1], ey[k + 1], ux[k + 1], uy[k + 1], nx, ny)
    rows, cols = belief.shape
    horizontal = ra == rb
    first, last = (ca, cb) if horizontal else (ra, rb)
    for along in range(min(first, last), max(first, last) + 1):
        r, c = (ra, along) if horizontal else (along, ca)
        if 0 <= r < rows and 0 <= c < cols and belief[r, c] == UNKNOWN:
            belief[r, c] = OCCUPIED
