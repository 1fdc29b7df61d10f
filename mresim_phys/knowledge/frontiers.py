"""Frontiers (phase 3b, knowledge): frontier clusters and targets from a belief grid.

A frontier cell is a FREE cell 8-adjacent to an UNKNOWN cell (cells outside the grid are not
unknown) that it can see: an UNKNOWN diagonal neighbour behind the corner where two OCCUPIED
cells meet (both cells orthogonally between them are walls) does not count. Walls are solid
cell squares, so no line of sight from the FREE cell reaches that unknown cell through the
corner, whatever the robot does there: without this rule every cell along a diagonal
(staircase) wall is a frontier that no scan can resolve (the original thickens walls 3 px
away from the robot, which closes these corners; its contour tracer takes a diagonal step
only between free cells). Clusters are the 8-connected components of frontier cells.
``find_frontiers`` extracts them with ``cv2.dilate`` (the candidate cells, then
:func:`sees_unknown` on those alone) and a union-find over the frontier
cells alone (:func:`label_cells`): labelling the whole 800x600 grid with
``cv2.connectedComponentsWithStats`` cost ~2.5 ms a replan, most of a replan's frontier
work. ``frontier_targets`` then picks, for every
cluster, the cheapest cell of a ``DistanceField`` from which the cluster is within reach.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numba import njit

from mresim_phys.planning.fields import DistanceField
from mresim_phys.types import (
    FREE,
    OCCUPIED,
    UNKNOWN,
    BeliefGrid,
    BoolGrid,
    FloatArray,
    IntArray,
)

_KERNEL_3X3 = np.ones((3, 3), dtype=np.uint8)
_EARLIER = ((0, -1), (-1, 0), (-1, -1), (-1, 1))  # 8-neighbours before a cell in raster order
_GATHER_CHUNK = 1 << 21  # elements per gather block in frontier_targets (bounds memory)


@dataclass(frozen=True, eq=False)
class Frontiers:
    """Frontier clusters of one belief grid, in raster order of their first cell.

    Attributes:
        sizes: (k,) number of cells of each cluster.
        centroids: (k, 2) world (x, y) mean of the cell centres of each cluster.
        cells_rc: (m, 2) (row, col) of every cell of the kept clusters, in raster order.
        cluster_of: (m,) cluster index (0..k-1) of each row of ``cells_rc``.
    """

    sizes: IntArray
    centroids: FloatArray
    cells_rc: IntArray
    cluster_of: IntArray

    def __len__(self) -> int:
        return len(self.sizes)


def _empty_frontiers() -> Frontiers:
    return Frontiers(
        sizes=np.zeros(0, dtype=np.intp),
        centroids=np.zeros((0, 2)),
        cells_rc=np.zeros((0, 2), dtype=np.intp),
        cluster_of=np.zeros(0, dtype=np.intp),
    )


@njit(cache=True, nogil=True)
def sees_unknown(belief: BeliefGrid, r: int, c: int) -> bool:
    """Whether cell (r, c) has an UNKNOWN 8-neighbour not hidden behind a wall corner.

    A diagonal neighbour is hidden when both cells orthogonally between them are OCCUPIED.
    """
    rows, cols = belief.shape
    for dr in range(-1, 2):
        for dc in range(-1, 2):
            rr, cc = r + dr, c + dc
            if not (0 <= rr < rows and 0 <= cc < cols) or belief[rr, cc] != UNKNOWN:
                continue
            if dr != 0 and dc != 0 and belief[rr, c] == OCCUPIED and belief[r, cc] == OCCUPIED:
                continue
            return True
    return False


@njit(cache=True, nogil=True)
def _keep_seeing(belief: BeliefGrid, mask: BoolGrid) -> None:
    """Clear the cells of ``mask`` whose only UNKNOWN neighbours are hidden (in place)."""
    rows, cols = mask.shape
    for r in range(rows):
        for c in range(cols):
            if mask[r, c] and not sees_unknown(belief, r, c):
                mask[r, c] = False


@njit(cache=True, nogil=True)
def any_frontier(belief: BeliefGrid, cells_rc: IntArray) -> bool:
    """Whether any of the cells (rows of (row, col)) is still a frontier cell of ``belief``."""
    for k in range(len(cells_rc)):
        r, c = cells_rc[k, 0], cells_rc[k, 1]
        if belief[r, c] == FREE and sees_unknown(belief, r, c):
            return True
    return False


def frontier_mask(belief: BeliefGrid) -> BoolGrid:
    """FREE cells with an UNKNOWN cell among their 8 neighbours that they can see.

    >>> b = np.array([[1, 1, 1, 1], [1, 1, 1, 0], [2, 1, 1, 1]], dtype=np.uint8)
    >>> frontier_mask(b).astype(int)
    array([[0, 0, 1, 1],
           [0, 0, 1, 0],
           [0, 0, 1, 1]])
    >>> wall = np.array([[1, 2, 0], [1, 1, 2], [1, 1, 1]], dtype=np.uint8)  # a staircase
    >>> frontier_mask(wall).astype(int)
    array([[0, 0, 0],
           [0, 0, 0],
           [0, 0, 0]])
    """
    unknown = (belief == UNKNOWN).view(np.uint8)
    # cv2's default dilation border never wins, so outside the grid is "not unknown".
    mask: BoolGrid = (cv2.dilate(unknown, _KERNEL_3X3) != 0) & (belief == FREE)
    _keep_seeing(belief, mask)
    return mask


@njit(cache=True, nogil=True)
def _find_root(parent: IntArray, i: int) -> int:
    """Root of ``i``'s set, halving the path on the way."""
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


@njit(cache=True, nogil=True)
def label_cells(flat: IntArray, width: int) -> IntArray:
    """8-connected components of the cells ``flat`` (indices row * width + col of a grid
    ``width`` wide, ascending): one label per cell, 0.. in raster order of each component's
    first cell. Union-find over the cells alone, each looking up its four neighbours that
    come earlier in raster order by binary search: O(k log k) for k cells, not O(grid)."""
    k = len(flat)
    parent = np.arange(k)
    for i in range(k):
        col = flat[i] % width
        for n in range(4):  # left, up-left, up, up-right: the neighbours labelled before
            if (n < 2 and col == 0) or (n == 3 and col == width - 1):
                continue
            target = flat[i] - (1, width + 1, width, width - 1)[n]
            j = np.searchsorted(flat[:i], target)
            if j < i and flat[j] == target:
                a, b = _find_root(parent, i), _find_root(parent, j)
                if a != b:
                    parent[max(a, b)] = min(a, b)  # the earlier cell's root stays the root
    labels = np.empty(k, dtype=np.intp)
    index = np.full(k, -1, dtype=np.intp)
    count = 0
    for i in range(k):
        root = _find_root(parent, i)
        if index[root] < 0:
            index[root] = count
            count += 1
        labels[i] = index[root]
    return labels


def find_frontiers(
    belief: BeliefGrid, min_size: int = 3, exclude: BoolGrid | None = None
) -> Frontiers:
    """Frontier clusters of a belief grid (see the module docstring).

    Only the bounding box of FREE cells (+1) is processed. Clusters with fewer than
    ``min_size`` cells are dropped.

    Args:
        belief: Belief grid (UNKNOWN / FREE / OCCUPIED).
        min_size: Smallest cluster kept, in cells.
        exclude: Cells never counted as frontier (e.g. ones a robot gave up on).

    Returns:
        The kept clusters, ordered by their first cell in raster order.
    """
    free_rows = np.flatnonzero((belief == FREE).any(axis=1))
    if free_rows.size == 0:
        return _empty_frontiers()
    r0, r1 = max(free_rows[0] - 1, 0), min(free_rows[-1] + 2, belief.shape[0])
    free_cols = np.flatnonzero((belief[r0:r1] == FREE).any(axis=0))
    c0, c1 = max(free_cols[0] - 1, 0), min(free_cols[-1] + 2, belief.shape[1])
    frontier = frontier_mask(belief[r0:r1, c0:c1])
    if exclude is not None:
        frontier &= ~exclude[r0:r1, c0:c1]
    if not frontier.any():  # (cv2.findNonZero gives None then)
        return _empty_frontiers()
    xy = cv2.findNonZero(frontier.view(np.uint8)).reshape(-1, 2).astype(np.intp)  # raster order
    rows, cols = xy[:, 1], xy[:, 0]
    width = c1 - c0
    seq = label_cells(rows * width + cols, width)
    counts = np.bincount(seq)
    sizes = counts.astype(np.intp)
    keep = sizes >= min_size
    new_index = np.full(len(sizes), -1, dtype=np.intp)
    new_index[keep] = np.arange(int(keep.sum()))
    cluster = new_index[seq]
    kept = cluster >= 0
    # exact means: sums of whole numbers are exact in float64, whatever their order
    centroids = np.column_stack(
        (np.bincount(seq, weights=cols) / counts, np.bincount(seq, weights=rows) / counts)
    )
    return Frontiers(
        sizes=sizes[keep],
        centroids=centroids[keep] + (c0 + 0.5, r0 + 0.5),
        cells_rc=np.column_stack((rows[kept] + r0, cols[kept] + c0)).astype(np.intp),
        cluster_of=cluster[kept],
    )


def _disc(reach: float) -> IntArray:
    """(n, 2) offsets (dr, dc) with dr^2 + dc^2 <= reach^2, in raster order."""
    radius = int(np.floor(reach))
    dr, dc = np.mgrid[-radius : radius + 1, -radius : radius + 1]
    inside = dr**2 + dc**2 <= reach**2
    return np.column_stack((dr[inside], dc[inside]))


def _candidate_costs(
    field: DistanceField, passable: BoolGrid, rows: IntArray, cols: IntArray
) -> FloatArray:
    """Field costs at cells (rows, cols) of any shape; inf off the field or not passable."""
    wr0, wc0 = field.origin  # the field's padded search window (inf on its border ring)
    hp, wp = field.window_costs.shape
    lr, lc = rows - wr0, cols - wc0
    inside = (lr >= 0) & (lr < hp) & (lc >= 0) & (lc < wp)
    values = np.full(rows.shape, np.inf)
    values[inside] = field.window_costs[lr[inside], lc[inside]]
    finite = np.isfinite(values)  # finite only on in-grid cells reached by the search
    values[finite] = np.where(passable[rows[finite], cols[finite]], values[finite], np.inf)
    return values


def _best_in_offsets(
    field: DistanceField, passable: BoolGrid, cells: IntArray, offsets: IntArray
) -> tuple[FloatArray, IntArray]:
    """For each cell, the min candidate cost over ``cell + offsets`` and its flat index.

    Ties go to the first offset; with raster-ordered offsets that is the smallest index.
    """
    width = passable.shape[1]
    best = np.empty(len(cells))
    where = np.empty(len(cells), dtype=np.intp)
    chunk = max(_GATHER_CHUNK // len(offsets), 1)
    for lo in range(0, len(cells), chunk):  # loop over blocks of cells, not cells
        rows = cells[lo : lo + chunk, :1] + offsets[:, 0]
        cols = cells[lo : lo + chunk, 1:] + offsets[:, 1]
        values = _candidate_costs(field, passable, rows, cols)
        arg = np.argmin(values, axis=1)
        pick = np.arange(len(arg))
        best[lo : lo + chunk] = values[pick, arg]
        where[lo : lo + chunk] = rows[pick, arg] * width + cols[pick, arg]
    return best, where


def _parent_direction(cells: IntArray) -> IntArray:
    """Index in ``_EARLIER`` of a cell's first earlier 8-neighbour in ``cells``; 4 if none."""
    width = int(cells[:, 1].max()) + 3
    flat = (cells[:, 0] + 1) * width + cells[:, 1] + 1
    known = np.sort(flat)
    group = np.full(len(cells), len(_EARLIER))
    for d, (dr, dc) in reversed(list(enumerate(_EARLIER))):  # first listed direction wins
        wanted = flat + dr * width + dc
        at = np.minimum(np.searchsorted(known, wanted), len(known) - 1)
        group[known[at] == wanted] = d
    return group


def frontier_targets(
    frontiers: Frontiers, field: DistanceField, passable: BoolGrid, reach: float
) -> tuple[IntArray, FloatArray]:
    """Cheapest place to look at each frontier cluster from.

    For cluster j the target is the passable cell within Euclidean distance ``reach``
    (cell centres) of any of its cells with the smallest cost in ``field``. Ties go to
    the smaller (row, col). The answer is exact. Each cell of the cluster contributes
    the disc of cells around it, minus the disc of an earlier 8-neighbour (in raster
    order) in the same cluster. Together these pieces cover the cluster's whole reach
    area, and a piece holds about 2 * reach cells instead of pi * reach^2.

    Args:
        frontiers: Clusters from ``find_frontiers``.
        field: Distance field of the robot.
        passable: Cells a target may be (normally the field's own passable mask).
        reach: Largest distance from target to frontier cell, in cells.

    Returns:
        ``targets`` (k, 2) (row, col), (-1, -1) where no cell qualifies, and their
        ``costs`` (k,), inf where no cell qualifies.
    """
    k = len(frontiers)
    targets = np.full((k, 2), -1, dtype=np.intp)
    costs = np.full(k, np.inf)
    if k == 0 or reach < 0 or field.start_rc is None:
        return targets, costs
    disc = _disc(reach)
    cells = frontiers.cells_rc
    group = _parent_direction(cells)
    best = np.full(len(cells), np.inf)
    where = np.zeros(len(cells), dtype=np.intp)
    for d in range(len(_EARLIER) + 1):
        sel = np.flatnonzero(group == d)
        offsets = disc
        if d < len(_EARLIER):  # the parent's disc is already covered by the parent
            offsets = disc[((disc - _EARLIER[d]) ** 2).sum(axis=1) > reach**2]
        if sel.size and offsets.size:
            best[sel], where[sel] = _best_in_offsets(field, passable, cells[sel], offsets)
    # Grouped min per cluster by (cost, row-major index): first row of each cluster.
    order = np.lexsort((where, best, frontiers.cluster_of))
    pick = order[np.r_[True, np.diff(frontiers.cluster_of[order]) != 0]]
    pick = pick[np.isfinite(best[pick])]
    clusters = frontiers.cluster_of[pick]
    costs[clusters] = best[pick]
    targets[clusters] = np.column_stack(np.divmod(where[pick], passable.shape[1]))
    return targets, costs
