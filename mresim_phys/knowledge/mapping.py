"""Mapping (phase 3): a robot's own occupancy grid, updated from its scans.

From each scan, as the original MRESim does:

* the free-space polygon spanned by the robot position and the ray end points
  (the end points alone for a 360 degree scan) is marked FREE: a cell is free iff
  its centre lies inside the polygon, plus the cells within ``NEAR_ROBOT`` of the
  robot; cells already OCCUPIED stay OCCUPIED unless a ray of the scan went through
  them (:func:`clear_contradicted`: walls are solid, so the map's wall there is false);
* every ray that ended on a wall below max range marks the wall cell it hit as
  OCCUPIED, and two consecutive hits on the same straight wall face, less than
  ``WALL_GAP`` apart, mark the face between them where still UNKNOWN (the original
  joins close hits the same way, so walls seen from afar do not look like frontiers);
* the safe space is the polygon of rays clipped to ``safe_fraction`` of the range
  (the original's 10 %): this scan's free cells within that radius, kept as a
  separate boolean grid for display.

A chord between two neighbouring ray ends can cut across a wall corner, so a
cell whose centre is within ``EDGE_BAND`` of a chord (along the chord's minor
axis: the cell a line rasteriser would draw) is kept only if it is nearer the
robot than both rays flanking it. This keeps wrongly-free wall cells well under
0.5 % of the free cells (tests/test_mapping.py).

All of it is one ``numba`` kernel (:func:`fold_scan`) over the polygon's bounding
window: a scanline fill of cell centres (even-odd rule, the crossings of every
polygon edge bucketed per row), the chord band, the face runs, the hit cells and
the safe disk, with no temporary grids (the kernels for the polygon's edges, the chord
band, the face runs, the hit cells and the false walls, are in ``knowledge/wall_marks.py``).
It replaced ~15 numpy/cv2 calls (an ROI
``cv2.fillPoly``, an erode + nonzero + arctan trim of the outline, vectorised face
runs and hit cells) whose fixed per-call overhead dominated: on the office map
(``benchmarks/bench_step.py``, 181 rays, old and new timed interleaved) a scan's
update went from ~330 us to ~42 us at range 100 and from ~370 us to ~52 us at
range 200, a factor of 7-8, which is what justifies the numba dependency. The
kernel is compiled once per machine (~7 s) and loaded from numba's on-disk cache
afterwards (~0.25 s per process, ``cache=True``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit
from numpy.typing import NDArray

from mresim_phys.knowledge.wall_marks import (
    NEAR_ROBOT,
    chord_band,
    clear_contradicted,
    hit_cell,
    mark_face,
)
from mresim_phys.types import FREE, OCCUPIED, UNKNOWN, BeliefGrid, BoolGrid, FloatArray, IntArray
from mresim_phys.world.space import Scan


@dataclass(frozen=True)
class Update:
    """Which cells one scan marked FREE: a mask over the window starting at (row0, col0)."""

    row0: int
    col0: int
    free: BoolGrid


def integrate_scan(
    belief: BeliefGrid,
    safe: BoolGrid,
    scan: Scan,
    safe_fraction: float,
    observed: NDArray[np.int32] | None = None,
    step: int = 0,
) -> Update | None:
    """Fold one scan into ``belief`` and ``safe`` in place; return the cells marked FREE.

    With ``observed`` (beliefs that hold each cell's latest observation) the scan also
    overwrites what it sees: cells inside its free polygon become FREE even if they were
    OCCUPIED (a moving obstacle has gone), the cells its rays hit are OCCUPIED, and both
    get ``step`` as their latest observation (:func:`refresh_seen`)."""
    angles = np.ascontiguousarray(scan.angles, dtype=np.float64)
    ranges = np.ascontiguousarray(scan.ranges, dtype=np.float64)
    wall_hit = np.ascontiguousarray(scan.wall_hit, dtype=np.bool_)
    ox, oy, max_range = float(scan.origin[0]), float(scan.origin[1]), float(scan.max_range)
    normals = np.ascontiguousarray(scan.normals, dtype=np.float64)
    row0, col0, free = _fold_alone(
        ox,
        oy,
        angles,
        ranges,
        normals,
        wall_hit,
        max_range,
        belief,
        safe,
        float(safe_fraction * max_range),
    )
    if row0 < 0:
        return None
    if observed is not None:
        refresh_seen(
            ox, oy, angles, ranges, normals, wall_hit, max_range, free, row0, col0, belief,
            observed, step,
        )  # fmt: skip
    return Update(row0, col0, free.view(bool))


@njit(cache=True, nogil=True)
def _fold_alone(
    ox: float,
    oy: float,
    angles: FloatArray,
    ranges: FloatArray,
    normals: FloatArray,
    wall_hit: BoolGrid,
    max_range: float,
    belief: BeliefGrid,
    safe: BoolGrid,
    safe_radius: float,
) -> tuple[int, int, BeliefGrid]:
    """:func:`fold_scan` called from Python. Numba's cache can lose the boxing environment
    of a kernel that another cached kernel also calls (``knowledge/scanfold.py``): its
    array result then fails to reach Python ("'descr' is NULL", seen when a noiseless run
    and then a noisy one ran in one process with warm caches). Each caller from Python is a
    kernel of its own."""
    radius = safe_radius
    return fold_scan(ox, oy, angles, ranges, normals, wall_hit, max_range, belief, safe, radius)


@njit(cache=True, nogil=True)
def refresh_seen(
    ox: float,
    oy: float,
    angles: FloatArray,
    ranges: FloatArray,
    normals: FloatArray,
    wall_hit: BoolGrid,
    max_range: float,
    free: BeliefGrid,
    row0: int,
    col0: int,
    belief: BeliefGrid,
    observed: NDArray[np.int32],
    step: int,
) -> None:
    """After :func:`fold_scan`: the scan's free cells (``free``, a window at row0, col0)
    become FREE whatever they held, then its hit cells OCCUPIED again (a hit wins within
    one scan, as in the fold); all of them were observed at ``step``."""
    h, w = free.shape
    for r in range(h):  # branch-free, so the row loop vectorises (~3x faster)
        cells, seen, row = (
            belief[r + row0, col0 : col0 + w],
            observed[r + row0, col0 : col0 + w],
            free[r],
        )
        for c in range(w):
            f = row[c] != 0
            cells[c] = FREE if f else cells[c]
            seen[c] = step if f else seen[c]
    rows, cols = belief.shape
    for k in range(len(angles)):
        if wall_hit[k] and ranges[k] < max_range:
            ux, uy = math.cos(angles[k]), math.sin(angles[k])
            ex, ey = ox + ranges[k] * ux, oy + ranges[k] * uy
            r, c = hit_cell(ex, ey, ux, uy, normals[k, 0], normals[k, 1])
            if 0 <= r < rows and 0 <= c < cols:
                belief[r, c] = OCCUPIED
                observed[r, c] = step


@njit(cache=True, nogil=True, inline="always")
def scan_polygon(
    ox: float, oy: float, angles: FloatArray, ex: FloatArray, ey: FloatArray
) -> tuple[FloatArray, FloatArray, bool]:
    """A scan's free polygon: the origin (unless the scan is a full circle: the gap behind
    its last ray no wider than the ray spacing) then the ray ends; and whether it is one."""
    n = len(angles)
    span = angles[n - 1] - angles[0]
    full = span + span / (n - 1) >= 2.0 * math.pi - 1e-9
    first = 0 if full else 1
    vx, vy = np.empty(n + first), np.empty(n + first)
    vx[0], vy[0] = ox, oy
    vx[first:] = ex
    vy[first:] = ey
    return vx, vy, full


@njit(cache=True, nogil=True, inline="always")
def polygon_window(
    vx: FloatArray, vy: FloatArray, rows: int, cols: int
) -> tuple[int, int, int, int]:
    """(r0, r1, c0, c1): the polygon's bounding window, a cell of margin, clipped to the map."""
    r0 = max(math.floor(vy.min()) - 1, 0)
    r1 = min(math.ceil(vy.max()) + 1, rows)
    c0 = max(math.floor(vx.min()) - 1, 0)
    c1 = min(math.ceil(vx.max()) + 1, cols)
    return r0, r1, c0, c1


@njit(cache=True, nogil=True)
def fold_scan(
    ox: float,
    oy: float,
    angles: FloatArray,
    ranges: FloatArray,
    normals: FloatArray,
    wall_hit: BoolGrid,
    max_range: float,
    belief: BeliefGrid,
    safe: BoolGrid,
    safe_radius: float,
) -> tuple[int, int, BeliefGrid]:
    """The whole map update of one scan; returns (row0, col0, free mask) or row0 = -1."""
    n = len(angles)
    rows, cols = belief.shape
    ux, uy = np.cos(angles), np.sin(angles)
    ex, ey = ox + ranges * ux, oy + ranges * uy
    vx, vy, full = scan_polygon(ox, oy, angles, ex, ey)
    r0, r1, c0, c1 = polygon_window(vx, vy, rows, cols)
    if r0 >= r1 or c0 >= c1:
        return -1, -1, np.zeros((0, 0), np.uint8)
    mask = np.zeros((r1 - r0, c1 - c0), np.uint8)
    trimmed = chord_band(ox, oy, ux, uy, ex, ey, ranges, n if full else n - 1, mask, r0, c0)
    walls = fill_centres(vx, vy, mask, belief, r0, c0)
    for i in range(len(trimmed)):
        mask[trimmed[i, 0], trimmed[i, 1]] = 0
    clear_contradicted(ox, oy, angles, ranges, walls, mask, belief, r0, c0)
    for r in range(max(int(oy - NEAR_ROBOT) - 1, r0), min(int(oy + NEAR_ROBOT) + 2, r1)):
        for c in range(max(int(ox - NEAR_ROBOT) - 1, c0), min(int(ox + NEAR_ROBOT) + 2, c1)):
            if (c + 0.5 - ox) ** 2 + (r + 0.5 - oy) ** 2 <= NEAR_ROBOT * NEAR_ROBOT:
                mask[r - r0, c - c0] = 1
                if belief[r, c] == UNKNOWN:
                    belief[r, c] = FREE
    on_wall = wall_hit & (ranges < max_range)
    for k in range(n - 1):
        if on_wall[k] and on_wall[k + 1]:
            mark_face(belief, normals, ex, ey, ux, uy, k)
    for k in range(n):
        if on_wall[k]:
            r, c = hit_cell(ex[k], ey[k], ux[k], uy[k], normals[k, 0], normals[k, 1])
            if 0 <= r < rows and 0 <= c < cols:
                belief[r, c] = OCCUPIED
    radius2 = safe_radius * safe_radius
    for r in range(max(int(oy - safe_radius), r0), min(int(oy + safe_radius) + 1, r1)):
        for c in range(max(int(ox - safe_radius), c0), min(int(ox + safe_radius) + 1, c1)):
            d2 = (c + 0.5 - ox) ** 2 + (r + 0.5 - oy) ** 2
            if mask[r - r0, c - c0] and d2 <= radius2 and belief[r, c] == FREE:
                safe[r, c] = True
    return r0, c0, mask


@njit(cache=True, nogil=True)
def fill_centres(
    vx: FloatArray, vy: FloatArray, mask: BeliefGrid, belief: BeliefGrid, r0: int, c0: int
) -> IntArray:
    """Scanline fill: mark the window cells whose centre is inside the polygon (even-odd).

    Every edge adds its x crossing to the rows whose centre line it crosses
    (half-open in y, so a vertex is counted once); each row's crossings, sorted,
    pair up into spans. Cells marked TRIMMED are skipped. Returns the window indices
    (``r * w + c``) of the OCCUPIED cells whose centre is inside: candidates for
    :func:`clear_contradicted`.
    """
    m = len(vx)
    h, w = mask.shape
    walls, found = np.empty(16, np.int64), 0
    starts = np.zeros(h + 1, np.int64)  # crossings per row, then row offsets
    for i in range(m):
        j = i + 1 if i + 1 < m else 0
        lo, hi = min(vy[i], vy[j]), max(vy[i], vy[j])
        ra = min(max(math.ceil(lo - 0.5) - r0, 0), h)
        rb = min(max(math.ceil(hi - 0.5) - r0, 0), h)
        for r in range(ra, rb):
            starts[r + 1] += 1
    for r in range(h):
        starts[r + 1] += starts[r]
    xs = np.empty(starts[h])
    fill = starts[:h].copy()
    for i in range(m):
        j = i + 1 if i + 1 < m else 0
        lo, hi = min(vy[i], vy[j]), max(vy[i], vy[j])
        ra = min(max(math.ceil(lo - 0.5) - r0, 0), h)
        rb = min(max(math.ceil(hi - 0.5) - r0, 0), h)
        slope = (vx[j] - vx[i]) / (vy[j] - vy[i]) if rb > ra else 0.0
        for r in range(ra, rb):
            xs[fill[r]] = vx[i] + (r + r0 + 0.5 - vy[i]) * slope
            fill[r] += 1
    for r in range(h):
        a, b = starts[r], starts[r + 1]
        for i in range(a + 1, b):  # insertion sort: a row crosses few edges
            x, j = xs[i], i - 1
            while j >= a and xs[j] > x:
                xs[j + 1] = xs[j]
                j -= 1
            xs[j + 1] = x
        row, known = mask[r], belief[r + r0, c0 : c0 + w]
        for i in range(a, b - 1, 2):
            ca = min(max(math.ceil(xs[i] - 0.5) - c0, 0), w)
            cb = min(max(math.ceil(xs[i + 1] - 0.5) - c0, 0), w)
            if span_walls(row, known, ca, cb):
                for c in range(ca, cb):
                    if row[c] == 0 and known[c] == OCCUPIED:
                        if found == len(walls):
                            walls = np.concatenate((walls, np.empty_like(walls)))
                        walls[found] = r * w + c
                        found += 1
            fill_span(row, known, ca, cb)
    return walls[:found]


@njit(cache=True, nogil=True, inline="always")
def span_walls(row: BeliefGrid, known: BeliefGrid, ca: int, cb: int) -> int:
    """How many cells of ``row[ca:cb]`` the fill will mark (mask 0) that ``known`` holds
    as OCCUPIED. Branch-free, so the compiler runs it on whole vectors of cells."""
    marks, cells = row[ca:cb], known[ca:cb]
    count = 0
    for c in range(len(marks)):
        count += (marks[c] == 0) & (cells[c] == OCCUPIED)
    return count


@njit(cache=True, nogil=True, inline="always")
def fill_span(row: BeliefGrid, known: BeliefGrid, ca: int, cb: int) -> None:
    """Mark the unmarked cells of ``row[ca:cb]`` (mask 0 -> 1) and make those ``known``
    holds UNKNOWN FREE. Branch-free (every cell of the span is written, most with the
    value it had), so the compiler runs it on whole vectors of cells: the fill takes 24 us
    a scan on the rooms map against 59 with a branch per cell (the same map, byte for byte).

    Both span loops index slices from 0: an index that may be negative (``row[c]`` for
    ``c`` from ``ca``) makes numba check for wrap-around at every cell, which stops the
    compiler from vectorising the loop at all (6x slower on a 114-cell span)."""
    marks, cells = row[ca:cb], known[ca:cb]
    for c in range(len(marks)):
        fresh = marks[c] == 0
        value = cells[c]
        cells[c] = FREE if fresh & (value == UNKNOWN) else value
        marks[c] = 1 if fresh else marks[c]


def mark_bump(belief: BeliefGrid, point: tuple[float, float], direction: FloatArray) -> bool:
    """Mark the cell a robot bumped into (just past ``point`` along ``direction``) OCCUPIED;
    return whether that taught the map anything (the cell was not OCCUPIED already)."""
    x, y = np.asarray(point) + 1e-3 * direction
    rows, cols = belief.shape
    if not (0 <= x < cols and 0 <= y < rows) or belief[int(y), int(x)] == OCCUPIED:
        return False
    belief[int(y), int(x)] = OCCUPIED
    return True


def merge_into(target: BeliefGrid, source: BeliefGrid) -> None:
    """Merge ``source`` into ``target`` in place: known beats unknown, obstacle beats free."""
    np.maximum(target, source, out=target)
