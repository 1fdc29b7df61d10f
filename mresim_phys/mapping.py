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


def ray_ends(scan: Scan) -> tuple[FloatArray, FloatArray]:
    """Unit directions (n, 2) and end points (n, 2) of every ray of a scan."""
    dirs = np.column_stack((np.cos(scan.angles), np.sin(scan.angles)))
    return dirs, np.asarray(scan.origin) + scan.ranges[:, None] * dirs


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
    dirs, ends = ray_ends(scan)
    if limit is not None:
        ends = np.asarray(scan.origin) + np.minimum(scan.ranges, limit)[:, None] * dirs
    return np.vstack((np.asarray(scan.origin)[None, :], ends))


def wall_cells(scan: Scan, shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """(rows, cols) of the wall cells the rays stopped on, inside the grid."""
    dirs, ends = ray_ends(scan)
    hit = scan.wall_hit & (scan.ranges < scan.max_range)
    inside = np.floor(ends[hit] + 1e-3 * dirs[hit]).astype(int)
    keep = (
        (inside[:, 0] >= 0)
        & (inside[:, 0] < shape[1])
        & (inside[:, 1] >= 0)
        & (inside[:, 1] < shape[0])
    )
    return inside[keep, 1], inside[keep, 0]


def face_links(scan: Scan) -> FloatArray:
    """Segments (k, 2, 2) joining consecutive hits on one straight wall face, inside the wall."""
    _, ends = ray_ends(scan)
    hit = scan.wall_hit & (scan.ranges < scan.max_range)
    n = scan.normals
    pair = hit[:-1] & hit[1:]
    same_dir = np.einsum("ij,ij->i", n[:-1], n[1:]) > NEAR_PARALLEL
    gap = ends[1:] - ends[:-1]
    on_face = np.abs(np.einsum("ij,ij->i", n[:-1], gap)) < 1e-6
    close = np.hypot(gap[:, 0], gap[:, 1]) < WALL_GAP
    k = np.flatnonzero(pair & same_dir & on_face & close)
    inward = -0.5 * n[k]
    return np.stack((ends[k] + inward, ends[k + 1] + inward), axis=1)


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
    mark_faces(roi, face_links(scan), r0, c0)
    rows, cols = wall_cells(scan, belief.shape)
    belief[rows, cols] = OCCUPIED
    safe_polygon = free_polygon(scan, limit=safe_fraction * scan.max_range)
    safe[r0:r1, c0:c1] |= fill_polygon(safe_polygon, window) & (roi == FREE)
    return Update(r0, c0, free)


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
    lower = np.clip(np.floor(k).astype(int), 0, n - 1)
    bound = np.minimum(scan.ranges[lower], scan.ranges[np.minimum(lower + 1, n - 1)])
    beyond = ((dist > bound) | (k > n - 1 + 1e-9)) & (dist > NEAR_ROBOT)
    free[rows[beyond], cols[beyond]] = False


def mark_faces(roi: BeliefGrid, links: FloatArray, row0: int, col0: int) -> None:
    """Mark the cells along joined wall faces OCCUPIED where they are still UNKNOWN."""
    if len(links) == 0:
        return
    lines = np.zeros(roi.shape, dtype=np.uint8)
    pixel = (links - (col0 + 0.5, row0 + 0.5)) * (1 << SUBPIXEL_BITS)
    segments = list(np.round(pixel).astype(np.int32))
    cv2.polylines(lines, segments, False, 1, thickness=1, lineType=cv2.LINE_8, shift=SUBPIXEL_BITS)
    roi[(lines == 1) & (roi == UNKNOWN)] = OCCUPIED


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
    """Truth-free cells ever marked FREE by anyone: the numerator of ``explored``.

    Kept incrementally from each scan's :class:`Update`, so the metric never
    needs a full-grid pass per step and can never decrease.
    """

    def __init__(self, reachable: BoolGrid) -> None:
        self.reachable = reachable
        self.total = int(reachable.sum())
        self.known = np.zeros_like(reachable)
        self.count = 0

    def add(self, update: Update) -> None:
        """Count the reachable cells of ``update`` not seen before."""
        h, w = update.free.shape
        seen = self.known[update.row0 : update.row0 + h, update.col0 : update.col0 + w]
        reach = self.reachable[update.row0 : update.row0 + h, update.col0 : update.col0 + w]
        new = update.free & reach & ~seen
        self.count += int(np.count_nonzero(new))
        seen |= new

    @property
    def fraction(self) -> float:
        """Known reachable free cells / all reachable free cells."""
        return self.count / self.total if self.total else 1.0
