"""Mapping (phase 3): a robot's own occupancy grid, updated from its scans.

From each scan, as the original MRESim does:

* the free-space polygon spanned by the robot position and the ray end points
  is marked FREE (rasterised with ``cv2.fillPoly`` on the polygon's bounding box);
* every ray that ended on a wall below max range marks the wall cell it hit as
  OCCUPIED, and two consecutive hits on the same straight wall face, less than
  ``WALL_GAP`` apart, mark the face between them (the original joins close hits
  the same way, so walls seen from afar do not look like frontiers);
* the safe space is the polygon of rays clipped to ``safe_fraction`` of the
  range (the original's 10 %), kept as a separate boolean grid for display.

``fillPoly`` paints every cell its outline touches, including wall cells the
rays stopped on; the outline cells are therefore re-checked with a cell-centre
rule (kept only if nearer than both rays flanking their direction), which keeps
wrongly-free wall cells well under 1 % of the free cells.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from .types import FREE, OCCUPIED, UNKNOWN, BeliefGrid, BoolGrid, FloatArray
from .world import Scan

WALL_GAP = 5.0  # cells: consecutive hits closer than this on one face are joined (original: 5 px)
SUBPIXEL_BITS = 4  # cv2 fixed-point precision for polygon vertices
NEAR_PARALLEL = 0.999  # cosine above which two face normals are the same face direction
NEAR_ROBOT = 1.0  # cells: the robot's own cell neighbourhood is free whatever the ray geometry
EDGE_KERNEL = np.ones((3, 3), dtype=np.uint8)


@dataclass(frozen=True)
class Update:
    """Which cells one scan marked FREE: a mask over the window starting at (row0, col0)."""

    row0: int
    col0: int
    free: BoolGrid


def polygon_window(points: FloatArray, shape: tuple[int, int]) -> tuple[int, int, int, int] | None:
    """Bounding window (row0, row1, col0, col1) of world points, clipped to the grid."""
    rows, cols = shape
    c0, r0 = np.floor(points.min(axis=0)).astype(int) - 1
    c1, r1 = np.ceil(points.max(axis=0)).astype(int) + 1
    r0, c0, r1, c1 = max(r0, 0), max(c0, 0), min(r1, rows), min(c1, cols)
    return None if r0 >= r1 or c0 >= c1 else (r0, r1, c0, c1)


def fill_polygon(points: FloatArray, window: tuple[int, int, int, int]) -> BoolGrid:
    """Cells of ``window`` covered by the polygon through world ``points``."""
    r0, r1, c0, c1 = window
    mask = np.zeros((r1 - r0, c1 - c0), dtype=np.uint8)
    pixel = (points - (c0 + 0.5, r0 + 0.5)) * (1 << SUBPIXEL_BITS)
    cv2.fillPoly(
        mask, [np.round(pixel).astype(np.int32)], 1, lineType=cv2.LINE_8, shift=SUBPIXEL_BITS
    )
    return mask.view(bool)


def free_polygon(scan: Scan, limit: float | None = None) -> FloatArray:
    """The robot position followed by the ray ends, optionally clipped to ``limit``."""
    ends = scan.ends
    if limit is not None:
        ends = np.asarray(scan.origin) + np.minimum(scan.ranges, limit)[:, None] * scan.dirs
    return np.vstack((np.asarray(scan.origin)[None, :], ends))


def wall_cells(scan: Scan, shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """(rows, cols) of the wall cells the rays stopped on, inside the grid."""
    hit = scan.on_wall
    inside = np.floor(scan.ends[hit] + 1e-3 * scan.dirs[hit]).astype(int)
    keep = (
        (inside[:, 0] >= 0)
        & (inside[:, 0] < shape[1])
        & (inside[:, 1] >= 0)
        & (inside[:, 1] < shape[0])
    )
    return inside[keep, 1], inside[keep, 0]


def face_links(scan: Scan) -> FloatArray:
    """Segments (k, 2, 2) joining consecutive hits on one straight wall face, inside the wall."""
    hit = scan.on_wall
    k = np.flatnonzero(hit[:-1] & hit[1:])
    if len(k) == 0:
        return np.zeros((0, 2, 2))
    n, a, b = scan.normals[k], scan.ends[k], scan.ends[k + 1]
    gap = b - a
    keep = (
        ((n * scan.normals[k + 1]).sum(axis=1) > NEAR_PARALLEL)  # same face direction
        & (np.abs((n * gap).sum(axis=1)) < 1e-6)  # on the same line
        & ((gap * gap).sum(axis=1) < WALL_GAP * WALL_GAP)
        & (np.abs(n).max(axis=1) > NEAR_PARALLEL)  # faces are cell edges
    )
    inward = -0.5 * n[keep]
    return np.stack((a[keep] + inward, b[keep] + inward), axis=1)


def integrate_scan(
    belief: BeliefGrid, safe: BoolGrid, scan: Scan, safe_fraction: float
) -> Update | None:
    """Fold one scan into ``belief`` and ``safe`` in place; return the cells marked FREE."""
    polygon = free_polygon(scan)
    window = polygon_window(polygon, belief.shape)
    if window is None:
        return None
    r0, r1, c0, c1 = window
    free = fill_polygon(polygon, window)
    trim_beyond_rays(free, r0, c0, scan)
    roi = belief[r0:r1, c0:c1]
    np.maximum(roi, free.view(np.uint8), out=roi)
    mark_faces(belief, face_links(scan))
    rows, cols = wall_cells(scan, belief.shape)
    belief[rows, cols] = OCCUPIED
    mark_safe(belief, safe, Update(r0, c0, free), scan.origin, safe_fraction * scan.max_range)
    return Update(r0, c0, free)


def mark_safe(
    belief: BeliefGrid, safe: BoolGrid, update: Update, origin: tuple[float, float], radius: float
) -> None:
    """Mark as safe the cells of this scan's free polygon within ``radius`` of the robot.

    The polygon of rays clipped to ``radius`` (the original's safe polygon) is the
    free polygon cut by the disk of that radius, so the disk is applied to the
    already-filled free window instead of filling a second polygon.
    """
    h, w = update.free.shape
    ox, oy = origin
    r0, r1 = max(int(oy - radius), update.row0), min(int(oy + radius) + 1, update.row0 + h)
    c0, c1 = max(int(ox - radius), update.col0), min(int(ox + radius) + 1, update.col0 + w)
    if r0 >= r1 or c0 >= c1:
        return
    dy = np.arange(r0, r1)[:, None] + 0.5 - oy
    dx = np.arange(c0, c1)[None, :] + 0.5 - ox
    inside = update.free[r0 - update.row0 : r1 - update.row0, c0 - update.col0 : c1 - update.col0]
    safe[r0:r1, c0:c1] |= (
        inside & (dx * dx + dy * dy <= radius * radius) & (belief[r0:r1, c0:c1] == FREE)
    )


def trim_beyond_rays(free: BoolGrid, row0: int, col0: int, scan: Scan) -> None:
    """Unmark boundary cells of the filled polygon whose centre lies past the rays around it.

    ``fillPoly`` paints every pixel its outline touches; this keeps a boundary
    cell only if its centre is nearer the robot than both rays flanking its
    direction (a cell-centre rule on the outline, where the errors are).
    """
    inner = cv2.erode(
        free.view(np.uint8), EDGE_KERNEL, borderType=cv2.BORDER_CONSTANT, borderValue=0
    )
    edge = free & ~inner.view(bool)
    rows, cols = np.nonzero(edge)
    dx = cols + (col0 + 0.5 - scan.origin[0])
    dy = rows + (row0 + 0.5 - scan.origin[1])
    dist = np.hypot(dx, dy)
    n = len(scan.angles)
    spacing = (scan.angles[-1] - scan.angles[0]) / (n - 1)
    k = np.mod(np.arctan2(dy, dx) - scan.angles[0], 2 * np.pi) / spacing
    lower = np.minimum(k.astype(np.intp), n - 1)  # k >= 0, so truncation is floor
    bound = np.minimum(scan.ranges[lower], scan.ranges[np.minimum(lower + 1, n - 1)])
    beyond = ((dist > bound) | (k > n - 1 + 1e-9)) & (dist > NEAR_ROBOT)
    free[rows[beyond], cols[beyond]] = False


def mark_faces(belief: BeliefGrid, links: FloatArray) -> None:
    """Mark the cells along joined wall faces OCCUPIED where they are still UNKNOWN.

    Wall segments are cell edges, so every link is horizontal or vertical and lies
    half a cell inside the wall: its cells are one run along a row or a column.
    """
    if len(links) == 0:
        return
    cells = np.floor(links).astype(np.intp)  # (k, 2 ends, (col, row))
    start, end = cells[:, 0, :], cells[:, 1, :]
    horizontal = start[:, 1] == end[:, 1]
    fixed = np.where(horizontal, start[:, 1], start[:, 0])
    first = np.where(horizontal, start[:, 0], start[:, 1])
    last = np.where(horizontal, end[:, 0], end[:, 1])
    low, counts = np.minimum(first, last), np.abs(last - first) + 1
    run = np.repeat(np.arange(len(cells)), counts)
    along = np.arange(len(run)) + np.repeat(low - (np.cumsum(counts) - counts), counts)
    rows = np.where(horizontal[run], fixed[run], along)
    cols = np.where(horizontal[run], along, fixed[run])
    height, width = belief.shape
    keep = (rows >= 0) & (rows < height) & (cols >= 0) & (cols < width)
    rows, cols = rows[keep], cols[keep]
    unknown = belief[rows, cols] == UNKNOWN
    belief[rows[unknown], cols[unknown]] = OCCUPIED


def mark_bump(belief: BeliefGrid, point: tuple[float, float], direction: FloatArray) -> None:
    """Mark the cell a robot bumped into (just past ``point`` along ``direction``) OCCUPIED."""
    x, y = np.asarray(point) + 1e-3 * direction
    rows, cols = belief.shape
    if 0 <= x < cols and 0 <= y < rows:
        belief[int(y), int(x)] = OCCUPIED


def merge_into(target: BeliefGrid, source: BeliefGrid) -> None:
    """Merge ``source`` into ``target`` in place: known beats unknown, obstacle beats free."""
    np.maximum(target, source, out=target)


class Coverage:
    """Reachable truth-free cells that some robot's map held as FREE at the end of a step.

    The numerator of ``explored``. Scans report the windows they touched
    (:meth:`touch`); at the end of the step only those windows are examined
    (:meth:`settle`), so the metric never needs a full-grid pass and never
    decreases. A run log's map deltas give exactly the same count on replay.
    """

    def __init__(self, reachable: BoolGrid) -> None:
        self.reachable = reachable
        self.total = int(reachable.sum())
        self.known = np.zeros_like(reachable)
        self.count = 0
        self._pending: list[tuple[BeliefGrid, int, int, int, int]] = []

    def touch(self, belief: BeliefGrid, update: Update) -> None:
        """Remember that ``update``'s window of ``belief`` changed this step."""
        h, w = update.free.shape
        self._pending.append((belief, update.row0, update.row0 + h, update.col0, update.col0 + w))

    def settle(self) -> None:
        """Count the reachable cells now FREE in the touched windows, not counted before."""
        for belief, r0, r1, c0, c1 in self._pending:
            self.add_cells(belief[r0:r1, c0:c1] == FREE, r0, c0)
        self._pending.clear()

    def add_cells(self, free: BoolGrid, row0: int, col0: int) -> None:
        """Count the reachable cells of ``free`` (a window at row0, col0) not seen before."""
        h, w = free.shape
        seen = self.known[row0 : row0 + h, col0 : col0 + w]
        new = free & self.reachable[row0 : row0 + h, col0 : col0 + w] & ~seen
        self.count += int(np.count_nonzero(new))
        seen |= new

    @property
    def fraction(self) -> float:
        """Known reachable free cells / all reachable free cells."""
        return self.count / self.total if self.total else 1.0
