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
the safe disk, with no temporary grids. It replaced ~15 numpy/cv2 calls (an ROI
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

from mresim_phys.types import FREE, OCCUPIED, UNKNOWN, BeliefGrid, BoolGrid, FloatArray, IntArray
from mresim_phys.world.space import Scan

WALL_GAP = 5.0  # cells: consecutive hits closer than this on one face are joined (original: 5 px)
NEAR_PARALLEL = 0.999  # cosine above which two face normals are the same face direction
NEAR_ROBOT = 1.0  # cells: the robot's own cell neighbourhood is free whatever the ray geometry
EDGE_BAND = 0.5 - 1e-6  # cells: chord band re-checked against the flanking rays (strict)
TRIMMED = 2  # mask value, inside the kernel only: a band cell excluded from the fill
THROUGH = 0.35  # cells: a ray this close to a cell's centre crossed its inside (0.7 cells)


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
def hit_cell(ex: float, ey: float, ux: float, uy: float, nx: float, ny: float) -> tuple[int, int]:
    """(row, col) of the wall cell a ray ending at (ex, ey) hit: across the surface
    (against its normal), on the ray's side of any other cell boundary through the end
    point. A ray that grazes a wall corner ends on two boundaries: the cell just past the
    end point along the ray is then the free one diagonally beyond the corner."""
    return math.floor(ey - 1e-3 * ny - 1e-6 * uy), math.floor(ex - 1e-3 * nx - 1e-6 * ux)


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
    span = angles[n - 1] - angles[0]
    # a full circle: the gap behind the last ray is no wider than the ray spacing
    full = span + span / (n - 1) >= 2.0 * math.pi - 1e-9
    # polygon: the origin (unless the scan is a full circle) then the ray ends
    first = 0 if full else 1
    m = n + first
    vx, vy = np.empty(m), np.empty(m)
    vx[0], vy[0] = ox, oy
    vx[first:] = ex
    vy[first:] = ey
    r0 = max(math.floor(vy.min()) - 1, 0)
    r1 = min(math.ceil(vy.max()) + 1, rows)
    c0 = max(math.floor(vx.min()) - 1, 0)
    c1 = min(math.ceil(vx.max()) + 1, cols)
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
        for i in range(a, b - 1, 2):
            ca = min(max(math.ceil(xs[i] - 0.5) - c0, 0), w)
            cb = min(max(math.ceil(xs[i + 1] - 0.5) - c0, 0), w)
            for c in range(ca, cb):
                if mask[r, c] == 0:
                    mask[r, c] = 1
                    if belief[r + r0, c + c0] == UNKNOWN:
                        belief[r + r0, c + c0] = FREE
                    elif belief[r + r0, c + c0] == OCCUPIED:
                        if found == len(walls):
                            walls = np.concatenate((walls, np.empty_like(walls)))
                        walls[found] = r * w + c
                        found += 1
    return walls[:found]


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
) -> IntArray:
    """Mark TRIMMED the band cells of every chord that lie past both flanking rays.

    A chord joins the ends of rays k and k+1; its band cells are those whose
    centre lies within EDGE_BAND of it along its minor axis, between the two rays,
    farther from the robot than the nearer ray end (and than NEAR_ROBOT).
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
