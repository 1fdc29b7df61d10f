"""Walls between points (world geometry, kernels): what a radio signal crosses on a grid.

An exact grid traversal (Amanatides-Woo) of the straight segment between two
points, in the world's continuous coordinates (cell (r, c) covers
[c, c+1] x [r, r+1]), counts

* ``runs``: the separate obstacle runs crossed (a thick wall counts once, as the
  original's 1-px line sampling does), and
* ``length``: the length of the segment inside obstacle cells (cells), for the
  wall-thickness attenuation mode.

:func:`walls_between` does it for a batch of segments and :func:`reach_along_rays`
marches rays outward from one agent until a path-loss signal drops below the
cut-off (the communication-region polygon). Both are ``numba`` kernels: counting
runs on the grid is exact for the run-length wall segments of ``world.py`` and
about 40x cheaper than collecting every pymunk hit (performance notes, section 8).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from mresim_phys.types import BoolGrid, FloatArray

_BIG = 1e30
TOUCH = 1e-9  # cells: a line this short inside a cell only touches it


@njit(cache=True, nogil=True, inline="always")
def _axis_setup(origin: float, delta: float, cell: int) -> tuple[int, float, float]:
    """(step, t of the first boundary, t per cell) of one axis of the traversal."""
    if delta > 0:
        return 1, (cell + 1 - origin) / delta, 1.0 / delta
    if delta < 0:
        return -1, (cell - origin) / delta, -1.0 / delta
    return 0, _BIG, _BIG


@njit(cache=True, nogil=True, inline="always")
def _next_cell(
    c: int, r: int, t_c: float, t_r: float, step_c: int, step_r: int, dt_c: float, dt_r: float
) -> tuple[int, int, float, float]:
    """One step of the traversal: into the column or the row whose boundary comes first."""
    if t_c <= t_r:
        return c + step_c, r, t_c + dt_c, t_r
    return c, r + step_r, t_c, t_r + dt_r


@njit(cache=True, nogil=True)
def segment_walls(
    occupied: BoolGrid, x0: float, y0: float, x1: float, y1: float
) -> tuple[int, float]:
    """(obstacle runs crossed, length inside obstacle cells) along (x0, y0) -> (x1, y1)."""
    rows, cols = occupied.shape
    dx, dy = x1 - x0, y1 - y0
    length = math.hypot(dx, dy)
    c, r = math.floor(x0), math.floor(y0)
    step_c, t_c, dt_c = _axis_setup(x0, dx, c)
    step_r, t_r, dt_r = _axis_setup(y0, dy, r)
    runs, inside, t = 0, 0.0, 0.0
    was_wall = False
    while t < 1.0:
        t_next = min(t_c, t_r, 1.0)
        if (t_next - t) * length > TOUCH:  # a cell only touched at a corner is not crossed
            wall = 0 <= r < rows and 0 <= c < cols and occupied[r, c]
            if wall:
                inside += (t_next - t) * length
                if not was_wall:
                    runs += 1
            was_wall = wall
        t = t_next
        c, r, t_c, t_r = _next_cell(c, r, t_c, t_r, step_c, step_r, dt_c, dt_r)
    return runs, inside


@njit(cache=True, nogil=True)
def walls_between(
    occupied: BoolGrid, starts: FloatArray, ends: FloatArray
) -> tuple[np.ndarray, FloatArray]:
    """Runs crossed and length inside walls for each segment ``starts[k] -> ends[k]``."""
    n = len(starts)
    runs = np.zeros(n, np.int64)
    inside = np.zeros(n, np.float64)
    for k in range(n):
        runs[k], inside[k] = segment_walls(
            occupied, starts[k, 0], starts[k, 1], ends[k, 0], ends[k, 1]
        )
    return runs, inside


@njit(cache=True, nogil=True)
def _free_limit(budget: float, loss: float, exponent10: float, reference: float) -> float:
    """Distance at which the log-distance loss beyond ``reference`` uses up ``budget - loss`` dB."""
    limit: float = reference * 10.0 ** ((budget - loss) / exponent10)
    return limit


@njit(cache=True, nogil=True)
def _run_out_inside(
    t: float,
    t_end: float,
    inside: float,
    budget: float,
    exponent10: float,
    reference: float,
    wall_db: float,
    cap: float,
) -> float:
    """Inside a wall cell from ``t`` (``inside`` cells of wall so far): where the budget
    runs out before ``t_end``, or -1 if it does not."""
    loss_end = min(inside + (t_end - t), cap) * wall_db
    if t_end <= _free_limit(budget, loss_end, exponent10, reference):
        return -1.0
    lo, hi = t, t_end
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        loss = min(inside + (mid - t), cap) * wall_db
        if mid > _free_limit(budget, loss, exponent10, reference):
            hi = mid
        else:
            lo = mid
    return lo


@njit(cache=True, nogil=True)
def _reach_one(
    occupied: BoolGrid,
    x0: float,
    y0: float,
    ux: float,
    uy: float,
    budget: float,
    exponent10: float,
    reference: float,
    wall_db: float,
    cap: float,
    per_cell: bool,
) -> float:
    """How far along (ux, uy) the signal stays at or above the cut-off."""
    rows, cols = occupied.shape
    c, r = math.floor(x0), math.floor(y0)
    step_c, t_c, dt_c = _axis_setup(x0, ux, c)
    step_r, t_r, dt_r = _axis_setup(y0, uy, r)
    t, walls, inside = 0.0, 0.0, 0.0
    was_wall = False
    limit = _free_limit(budget, 0.0, exponent10, reference)
    while t < limit:
        if not (0 <= r < rows and 0 <= c < cols):
            return limit  # beyond the map nothing attenuates more
        t_next = min(t_c, t_r)
        if t_next - t > TOUCH:  # a cell only touched at a corner is not crossed
            wall = occupied[r, c]
            if wall and per_cell:
                end = min(t_next, limit)
                out = _run_out_inside(t, end, inside, budget, exponent10, reference, wall_db, cap)
                if out >= 0.0:
                    return out
                inside += t_next - t
            elif wall and not was_wall:
                walls += 1.0
            loss = min(inside if per_cell else walls, cap) * wall_db
            limit = _free_limit(budget, loss, exponent10, reference)
            if limit <= t:
                return t
            was_wall = wall
        t = t_next
        c, r, t_c, t_r = _next_cell(c, r, t_c, t_r, step_c, step_r, dt_c, dt_r)
    return limit


@njit(cache=True, nogil=True)
def reach_along_rays(
    occupied: BoolGrid,
    x0: float,
    y0: float,
    angles: FloatArray,
    budget: float,
    exponent10: float,
    reference: float,
    wall_db: float,
    cap: float,
    per_cell: bool,
) -> FloatArray:
    """Per ray, the distance where ``budget - 10 n log10(d / reference) - walls`` hits 0.

    ``budget`` is transmit-side power minus the cut-off (dB), ``exponent10`` is
    10 x the path-loss exponent; walls cost ``wall_db`` each (capped at ``cap``
    walls) or, with ``per_cell``, ``wall_db`` per cell of wall crossed.
    """
    out = np.empty(len(angles))
    for k in range(len(angles)):
        out[k] = _reach_one(
            occupied,
            x0,
            y0,
            math.cos(angles[k]),
            math.sin(angles[k]),
            budget,
            exponent10,
            reference,
            wall_db,
            cap,
            per_cell,
        )
    return out
