"""Sensing kernel (phase 2): a fan of rays through the truth grid in one compiled call.

The Space's walls lie exactly on the boundaries between occupied and free cells of
the truth grid (``maps.wall_segments``; changes and movable obstacles write that grid
in place), so the first wall a ray meets is the first occupied cell it enters: an
exact grid traversal (Amanatides & Woo) finds it without a Python call per ray.
Robots that block rays are circles, intersected analytically in the same loop.

Distances are exact: ``t = (X - ox) / dx`` for the first boundary ``x = X`` of an
occupied cell (likewise in y). A ray that passes exactly through a cell corner
(to within 1e-9 cells, e.g. a 45 degree ray from a cell centre) stops there if any
of the three cells beyond the corner is occupied: a ray does not slip between two
diagonally touching wall cells, and a ray grazing a wall corner touches it, as a
segment query touches a segment's end point (its normal faces the cell it touched: across
that cell's side, or diagonally back when only the diagonal cell is a wall, so the map
marks that cell, ``knowledge.wall_marks.hit_cell``); likewise a ray running exactly along a cell
boundary line (a robot on a whole coordinate looking along an axis) touches the cells on
both sides of it. Outside the map is wall.

Typical use (``World.cast_rays`` does this)::

    ranges, normals, wall_hit = np.empty(n), np.empty((n, 2)), np.empty(n, bool)
    cast_fan(occupied, x, y, angles, 200.0, circles, ranges, normals, wall_hit)
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from mresim_phys.types import BoolGrid, FloatArray

CORNER_EPS = 1e-9  # crossings closer than this (in ray length) pass through a cell corner
AXIS_EPS = 1e-12  # a direction component below this runs along a grid line
NO_TWIN = -(2**31)  # no twin row or column
DIAGONAL = math.sqrt(0.5)  # a corner's normal component, towards the ray


@njit(cache=True, nogil=True)
def _occupied(grid: BoolGrid, row: int, col: int) -> bool:
    """Cell (row, col) is a wall; everything outside the map is."""
    rows, cols = grid.shape
    if row < 0 or col < 0 or row >= rows or col >= cols:
        return True
    return bool(grid[row, col])


@njit(cache=True, nogil=True, error_model="numpy")
def _grid_hit(
    grid: BoolGrid, ox: float, oy: float, dx: float, dy: float, max_range: float
) -> tuple[float, float, float]:
    """(t, nx, ny) of the first occupied cell a ray enters, or (inf, 0, 0) within range.

    Compiled with numpy's error model: a division here is never by zero (a crossing in an
    axis is computed only once the ray has stepped in it, so its direction component is
    not 0), and without Python's check before each division the cast is ~7 % faster (the
    same floats)."""
    col, row = math.floor(ox), math.floor(oy)
    sx = 1 if dx > 0 else (-1 if dx < 0 else 0)
    sy = 1 if dy > 0 else (-1 if dy < 0 else 0)
    bx = col + (1 if sx > 0 else 0)  # the next vertical boundary x = bx
    by = row + (1 if sy > 0 else 0)  # the next horizontal boundary y = by
    # a ray along a boundary line (x or y whole, the ray parallel to it) touches the
    # cells on both sides of the line: the twin column (row) is checked too
    twin_col = col - 1 if abs(dx) < AXIS_EPS and ox == col else NO_TWIN
    twin_row = row - 1 if abs(dy) < AXIS_EPS and oy == row else NO_TWIN
    # each crossing distance is recomputed from its boundary only when that boundary moves
    # (the same division as before, so the same floats, one division a cell instead of two)
    tx = (bx - ox) / dx if sx != 0 else math.inf
    ty = (by - oy) / dy if sy != 0 else math.inf
    while True:
        t = min(tx, ty)
        if t > max_range:
            return math.inf, 0.0, 0.0
        if tx < ty - CORNER_EPS:
            col += sx
            bx += sx
            if _occupied(grid, row, col) or (
                twin_row != NO_TWIN and _occupied(grid, twin_row, col)
            ):
                return tx, float(-sx), 0.0
            tx = (bx - ox) / dx
        elif ty < tx - CORNER_EPS:
            row += sy
            by += sy
            if _occupied(grid, row, col) or (
                twin_col != NO_TWIN and _occupied(grid, row, twin_col)
            ):
                return ty, 0.0, float(-sy)
            ty = (by - oy) / dy
        else:  # through a corner: stop if any of the three cells beyond it is a wall
            if _occupied(grid, row, col + sx):
                return t, float(-sx), 0.0
            if _occupied(grid, row + sy, col):
                return t, 0.0, float(-sy)
            if _occupied(grid, row + sy, col + sx):  # only the diagonal cell: its corner
                return t, -sx * DIAGONAL, -sy * DIAGONAL
            col += sx
            row += sy
            bx += sx
            by += sy
            tx = (bx - ox) / dx if sx != 0 else math.inf
            ty = (by - oy) / dy if sy != 0 else math.inf


@njit(cache=True, nogil=True)
def _circle_hit(
    circles: FloatArray, ox: float, oy: float, dx: float, dy: float, limit: float
) -> tuple[float, float, float]:
    """(t, nx, ny) where the ray first enters one of ``circles`` (rows x, y, r) before
    ``limit``, or (inf, 0, 0). A ray starting inside a circle is not stopped by it."""
    best, nx, ny = math.inf, 0.0, 0.0
    for i in range(circles.shape[0]):
        cx, cy, r = circles[i, 0] - ox, circles[i, 1] - oy, circles[i, 2]
        along = cx * dx + cy * dy
        off2 = cx * cx + cy * cy - along * along
        if along <= 0.0 or off2 > r * r:
            continue
        t = along - math.sqrt(r * r - off2)
        if 0.0 < t <= limit and t < best:
            best = t
            nx, ny = (dx * t - cx) / r, (dy * t - cy) / r
    return best, nx, ny


@njit(cache=True, nogil=True)
def cast_fan(
    grid: BoolGrid,
    ox: float,
    oy: float,
    angles: FloatArray,
    max_range: float,
    circles: FloatArray,
    ranges: FloatArray,
    normals: FloatArray,
    wall_hit: np.ndarray,
) -> None:
    """Cast one ray per angle from (ox, oy) through ``grid`` and ``circles``.

    Writes per ray the distance to the first hit (or ``max_range``), the unit surface
    normal there (facing the ray; zeros without a hit) and whether a wall (not a
    circle) was hit.
    """
    for k in range(len(angles)):
        dx, dy = math.cos(angles[k]), math.sin(angles[k])
        t, nx, ny = _grid_hit(grid, ox, oy, dx, dy, max_range)
        wall = t <= max_range
        if circles.shape[0] > 0:
            tc, cnx, cny = _circle_hit(circles, ox, oy, dx, dy, min(t, max_range))
            if tc < t:
                t, nx, ny, wall = tc, cnx, cny, False
        if t <= max_range:
            ranges[k], normals[k, 0], normals[k, 1], wall_hit[k] = t, nx, ny, wall
        else:
            ranges[k], normals[k, 0], normals[k, 1], wall_hit[k] = max_range, 0.0, 0.0, False
