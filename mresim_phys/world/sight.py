"""World (phase 1, geometry): compiled line-of-sight kernels for the explorable area.

A cell C is *seen* from a position P (both cell centres) when the closed segment between
the centres touches no occupied cell, cells taken as closed unit squares: a segment that
passes exactly through a grid corner touches all four cells around it, so two obstacles
meeting at a corner block sight as they block robots (``world/maps.py``). Within the grid
the touched cells are the segment's *supercover*, walked by :func:`clear_line` with
integer arithmetic only (no rounding can decide a tangency).

:func:`decide` answers, for a cell, whether some reachable position within the sensor
range sees it, and which (the *witness*); :func:`see_cells` decides a list of cells,
:func:`see_again` a window after a change of the world. It tries cheap guesses first
(the witness the cell had before, those of its neighbours: sight is coherent), then
searches: a shadow cast from C itself, octant by octant, depth (Chebyshev distance) by
depth across all octants at once (a first-in first-out queue of lit slope intervals), so
the nearest positions are tried first and the search ends at the first position that
:func:`clear_line` confirms. The shadows are those of the occupied squares met at
smaller depths within the octant, widened by :data:`SLACK` so rounding only ever lets
more candidates through; the exact segment test decides. A search may be limited to the
directions of a box (:func:`box_sector`): after a change of the world, a cell nothing
saw before can only be seen along a segment that meets the change.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numpy.typing import NDArray

from mresim_phys.types import BoolGrid

SLACK = 1e-9  # slopes: shadows are narrowed (lit intervals widened) by this much
NONE = -1  # no witness
FULL, SECTOR, KEEP = 0, 1, 2  # decide's modes: search all around, towards a box, or not
# octant k maps (depth d, offset y), 0 <= y <= d, to (row, col) offsets d*D[k] + y*Y[k]
OCTANT_ROW_D = np.array([0, 1, 1, 0, 0, -1, -1, 0], dtype=np.int64)
OCTANT_ROW_Y = np.array([1, 0, 0, 1, -1, 0, 0, -1], dtype=np.int64)
OCTANT_COL_D = np.array([1, 0, 0, -1, -1, 0, 0, 1], dtype=np.int64)
OCTANT_COL_Y = np.array([0, 1, -1, 0, 0, -1, 1, 0], dtype=np.int64)
ALL_AROUND = np.array([[0.0, 1.0]] * 8)  # every octant's slopes, unrestricted


@njit(cache=True, nogil=True)
def clear_line(occupied: BoolGrid, r0: int, c0: int, r1: int, c1: int) -> bool:
    """Whether the closed segment between the centres of cells (r0, c0) and (r1, c1)
    touches no occupied cell (both cells inside the grid; the first is not tested).

    The supercover walk: ``error`` compares the distances to the next column and row
    boundary (doubled, in whole numbers); at 0 the segment passes through a corner and
    both cells beside the diagonal step touch it.
    """
    dr, dc = abs(r1 - r0), abs(c1 - c0)
    sr = 1 if r1 > r0 else -1
    sc = 1 if c1 > c0 else -1
    error = dc - dr
    r, c = r0, c0
    while r != r1 or c != c1:
        if error > 0:
            c += sc
            error -= 2 * dr
        elif error < 0:
            r += sr
            error += 2 * dc
        else:
            if occupied[r, c + sc] or occupied[r + sr, c]:
                return False
            r += sr
            c += sc
            error += 2 * (dc - dr)
        if occupied[r, c]:
            return False
    return True


@njit(cache=True, nogil=True)
def _witness_ok(
    occupied: BoolGrid, reach: BoolGrid, row: int, col: int, flat: int, range2: float
) -> bool:
    """Whether reachable position ``flat`` (a flat index, or NONE) sees cell (row, col)."""
    if flat < 0:
        return False
    cols = occupied.shape[1]
    pr, pc = flat // cols, flat % cols
    if not reach[pr, pc]:
        return False
    if (pr - row) ** 2 + (pc - col) ** 2 > range2:
        return False
    return clear_line(occupied, pr, pc, row, col)


@njit(cache=True, nogil=True)
def _push(queue: NDArray[np.float64], tail: int, k: int, d: int, lo: float, hi: float) -> int:
    """Append (octant, depth, lo, hi) to the ring buffer ``queue``; the new tail."""
    slot = tail % queue.shape[0]
    queue[slot, 0], queue[slot, 1], queue[slot, 2], queue[slot, 3] = k, d, lo, hi
    return tail + 1


@njit(cache=True, nogil=True)
def shadow_search(
    occupied: BoolGrid,
    reach: BoolGrid,
    row: int,
    col: int,
    sensor_range: float,
    slopes: NDArray[np.float64],
    queue: NDArray[np.float64],
) -> int:
    """The first reachable position within ``sensor_range`` that sees cell (row, col) by
    a shadow cast from it, nearest depths first; its flat index, or NONE.

    ``slopes`` (8, 2): each octant's lit slope interval at the start (lo > hi: none);
    ``queue``: a scratch ring buffer of at least ``16 * (range + 3)`` rows.
    """
    rows, cols = occupied.shape
    range2 = sensor_range * sensor_range
    deepest = math.floor(sensor_range)
    head = tail = 0
    for k in range(8):
        if slopes[k, 0] <= slopes[k, 1]:
            tail = _push(queue, tail, k, 1, slopes[k, 0], slopes[k, 1])
    while head < tail:
        slot = head % queue.shape[0]
        k, d = int(queue[slot, 0]), int(queue[slot, 1])
        lo, hi = queue[slot, 2], queue[slot, 3]
        head += 1
        if d > deepest:
            continue
        first = max(0, math.ceil(lo * (d - 0.5) - 0.5 - SLACK))
        last = min(d, math.floor(hi * (d + 0.5) + 0.5 + SLACK))
        run_lo, open_run = lo, False
        for y in range(first, last + 1):
            r = row + d * OCTANT_ROW_D[k] + y * OCTANT_ROW_Y[k]
            c = col + d * OCTANT_COL_D[k] + y * OCTANT_COL_Y[k]
            if r < 0 or c < 0 or r >= rows or c >= cols or occupied[r, c]:
                if open_run:
                    wall_lo = (y - 0.5) / (d + 0.5) + SLACK
                    tail = _push(queue, tail, k, d + 1, run_lo, min(hi, wall_lo))
                open_run = False
                run_lo = max(run_lo, (y + 0.5) / (d - 0.5) - SLACK)
                continue
            open_run = True
            if reach[r, c] and d * d + y * y <= range2:
                slope = y / d
                if lo - SLACK <= slope <= hi + SLACK and clear_line(occupied, r, c, row, col):
                    flat: int = r * cols + c
                    return flat
        if open_run and run_lo <= hi:
            tail = _push(queue, tail, k, d + 1, run_lo, hi)
    return NONE


@njit(cache=True, nogil=True)
def box_sector(row: int, col: int, box: NDArray[np.int64], out: NDArray[np.float64]) -> None:
    """Into ``out`` (8, 2): each octant's slopes towards the cells of ``box`` (row0, row1,
    col0, col1) from the centre of cell (row, col), widened by :data:`SLACK`; every
    direction when the cell is inside or next to the box."""
    top, bottom = box[0] - 0.5 - row, box[1] - 0.5 - row
    left, right = box[2] - 0.5 - col, box[3] - 0.5 - col
    if top <= 0.5 and bottom >= -0.5 and left <= 0.5 and right >= -0.5:
        out[:, 0], out[:, 1] = 0.0, 1.0
        return
    middle = math.atan2((top + bottom) / 2, (left + right) / 2)
    low, high = math.pi, -math.pi
    for y in (top, bottom):
        for x in (left, right):
            turn = math.atan2(y, x) - middle
            turn -= 2 * math.pi * math.floor((turn + math.pi) / (2 * math.pi))
            low, high = min(low, turn), max(high, turn)
    quarter = math.pi / 4
    for k in range(8):
        out[k, 0], out[k, 1] = 1.0, 0.0
        base = k * quarter
        for shift in (-2 * math.pi, 0.0, 2 * math.pi):
            u0 = max(middle + low + shift, base) - base
            u1 = min(middle + high + shift, base + quarter) - base
            if u0 <= u1:
                if k % 2 == 1:
                    u0, u1 = quarter - u1, quarter - u0
                out[k, 0] = max(math.tan(u0) - SLACK, 0.0)
                out[k, 1] = min(math.tan(u1) + SLACK, 1.0)


@njit(cache=True, nogil=True)
def decide(
    occupied: BoolGrid,
    reach: BoolGrid,
    row: int,
    col: int,
    mode: int,
    sensor_range: float,
    toward: NDArray[np.int64],
    witness: NDArray[np.int32],
    scratch: tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int64]],
) -> bool:
    """Whether a reachable position within ``sensor_range`` sees cell (row, col); its
    witness (flat index, or NONE) is written into the flat ``witness`` grid, which also
    holds the guesses tried first (the cell's own witness, its neighbours').

    ``mode``: FULL searches all around, SECTOR only towards the box ``toward``, KEEP only
    tries the guesses. ``scratch``: the search's queue, slopes and guesses."""
    queue, slopes, guesses = scratch
    rows, cols = occupied.shape
    range2 = sensor_range * sensor_range
    here = row * cols + col
    guesses[0] = witness[here]
    guesses[1] = witness[here - 1] if col > 0 else NONE
    guesses[2] = witness[here - cols] if row > 0 else NONE
    guesses[3] = witness[here + 1] if col + 1 < cols else NONE
    guesses[4] = witness[here + cols] if row + 1 < rows else NONE
    found = NONE
    for guess in guesses:
        if _witness_ok(occupied, reach, row, col, int(guess), range2):
            found = int(guess)
            break
    if found == NONE and mode != KEEP:
        if mode == SECTOR:
            box_sector(row, col, toward, slopes)
        else:
            slopes[:, 0], slopes[:, 1] = 0.0, 1.0
        found = shadow_search(occupied, reach, row, col, sensor_range, slopes, queue)
    witness[here] = found
    return found != NONE


@njit(cache=True, nogil=True)
def scratch_for(
    sensor_range: float,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int64]]:
    """The scratch arrays of :func:`decide` for a search within ``sensor_range``."""
    queue = np.empty((16 * (int(sensor_range) + 3), 4), dtype=np.float64)
    return queue, np.empty((8, 2), dtype=np.float64), np.empty(5, dtype=np.int64)


@njit(cache=True, nogil=True)
def see_cells(
    occupied: BoolGrid,
    reach: BoolGrid,
    cells: NDArray[np.int64],
    sensor_range: float,
    witness: NDArray[np.int32],
    seen: BoolGrid,
) -> None:
    """:func:`decide` (all around) each cell (row, col) of ``cells`` into ``seen``. Cells
    are taken in the given order, so a raster order lets each cell try the witnesses
    just found for the cells left of it and above it."""
    scratch = scratch_for(sensor_range)
    nowhere = np.zeros(4, dtype=np.int64)
    for n in range(cells.shape[0]):
        row, col = cells[n, 0], cells[n, 1]
        seen[row, col] = decide(
            occupied, reach, row, col, FULL, sensor_range, nowhere, witness, scratch
        )


WORD = 8  # cells looked at as one uint64 by see_again
ONES = np.uint64(0x0101010101010101)  # a word of eight True cells


def words(grid: BoolGrid) -> NDArray[np.uint64]:
    """``grid`` (bool, C-contiguous) as rows of uint64 words of 8 cells; an empty
    (rows, 0) array when its rows are not a whole number of words (then
    :func:`see_again` looks at every cell)."""
    if grid.shape[1] % WORD or not grid.flags.c_contiguous:
        return np.zeros((grid.shape[0], 0), np.uint64)
    return grid.view(np.uint64)


@njit(cache=True, nogil=True)
def settled(
    occupied: NDArray[np.uint64], near: NDArray[np.uint64], seen: NDArray[np.uint64],
    r: int, c: int, end: int,
) -> bool:  # fmt: skip
    """Whether the 8 cells from (r, c) (c a whole word, within ``end``) are each either
    near and seen or occupied and unseen: nothing to decide (word views, :func:`words`)."""
    if occupied.shape[1] == 0 or c % WORD or c + WORD > end:
        return False
    w = c // WORD
    o, n, s = occupied[r, w], near[r, w], seen[r, w]
    done: bool = ((n & ~o & s) | (o & ~s)) & ONES == ONES
    return done


@njit(cache=True, nogil=True)
def see_again(
    occupied: BoolGrid,
    reach: BoolGrid,
    near: BoolGrid,
    seen: BoolGrid,
    witness: NDArray[np.int32],
    window: NDArray[np.int64],
    flipped: BoolGrid,
    flipped_at: NDArray[np.int64],
    grew: bool,
    toward: NDArray[np.int64],
    sensor_range: float,
    grids: tuple[NDArray[np.uint64], NDArray[np.uint64], NDArray[np.uint64]],
    left_rows: NDArray[np.int32],
    changed_rows: NDArray[np.int64],
) -> NDArray[np.int64]:
    """Decide again the cells of ``window`` (row0, row1, col0, col1) after a change: free
    cells in ``near`` are seen; each other free cell is decided (:func:`decide`) all
    around if it was seen before or flipped (``flipped`` at (row, col) ``flipped_at``),
    else towards ``toward`` if some cell became free (``grew``), else it stays unseen.
    ``grids``: word views of ``occupied``, ``near`` and ``seen`` (:func:`words`), to skip
    eight settled cells at a time; ``left_rows``: each row's free cells not ``near``, to
    skip rows without any outside ``changed_rows`` (row0, row1: where ``near`` or the
    truth changed). Returns the box of the cells whose ``seen`` changed (empty: row0 >=
    row1)."""
    scratch = scratch_for(sensor_range)
    changed = np.array([window[1], window[0], window[3], window[2]], dtype=np.int64)
    f_rows, f_cols = flipped.shape
    for r in range(window[0], window[1]):
        if left_rows[r] == 0 and not changed_rows[0] <= r < changed_rows[1]:
            continue
        c = window[2]
        while c < window[3]:
            if settled(grids[0], grids[1], grids[2], r, c, window[3]):
                c += WORD
                continue
            was = seen[r, c]
            if occupied[r, c]:
                now = False
            elif near[r, c]:
                now = True
            else:
                fr, fc = r - flipped_at[0], c - flipped_at[1]
                flip = 0 <= fr < f_rows and 0 <= fc < f_cols and flipped[fr, fc]
                mode = FULL if was or flip else (SECTOR if grew else KEEP)
                now = mode != KEEP and decide(
                    occupied, reach, r, c, mode, sensor_range, toward, witness, scratch
                )
            if now != was:
                seen[r, c] = now
                changed[0], changed[1] = min(changed[0], r), max(changed[1], r + 1)
                changed[2], changed[3] = min(changed[2], c), max(changed[3], c + 1)
            c += 1
    return changed
