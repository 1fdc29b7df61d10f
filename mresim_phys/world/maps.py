"""Phase 1 (geometry), pure kernels: occupancy grid -> exact wall segments, reachable free space.

:func:`wall_segments` turns a boolean occupancy grid into the static pymunk wall segments
of the world. It is the run-length merge of cell edges (2.5 ms on the 800x600 office,
``docs/performance.md``, Kernels), the only converter that is exact: every segment lies
on the boundary between an occupied and a free cell, every such unit edge is covered once,
and collinear neighbouring edges with the same occupied side are merged into one segment.
Two occupied cells that touch only at a corner produce segments that meet at that vertex,
so no ray slips through the diagonal gap.

:func:`free_components_mask` gives the free space reachable from the robots' start
points (4-connected, so a diagonal squeeze between two corner-touching obstacles is not
a passage): the denominator of the explored-area metric.

:func:`edge_segments` rebuilds the segments of a window of lines when the world changes
(``world/wallset.py``): the same run-length merge over a *kinds* grid (0 free, 1 static
wall, 2 movable obstacle), so runs also break where the kind of the occupied side changes.
On a grid of kinds 0/1 it gives exactly the rows :func:`wall_segments` gives.

Grid convention (see :mod:`mresim_phys.types`): cell (r, c) covers x in [c, c+1) and
y in [r, r+1); cells outside the grid count as occupied.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage

from mresim_phys.errors import MapError
from mresim_phys.types import BoolGrid, FloatArray

__all__ = [
    "FOUR_CONNECTED",
    "KindGrid",
    "connected_to",
    "edge_segments",
    "free_components_mask",
    "padded_kinds",
    "seed_cells",
    "wall_segments",
]

KindGrid = NDArray[np.int8]  # 0 free, 1 static wall, 2 movable obstacle; padded by one wall cell
KindArray = NDArray[np.int8]

FOUR_CONNECTED = ndimage.generate_binary_structure(2, 1)


def _runs(steps: NDArray[np.int8]) -> tuple[NDArray[np.intp], ...]:
    """Find maximal runs of equal non-zero values along each line of ``steps``.

    Args:
        steps: ``(lines, n + 1)`` array of -1/0/+1 (the occupancy change across each unit
            edge of a line); the last column is a zero separator between lines.

    Returns:
        ``(line, start, end, sign)`` arrays, one entry per run, in row-major order;
        the run covers unit edges ``start .. end-1`` of its line.

    >>> line, start, end, sign = _runs(np.array([[0, 1, 1, -1, 0, 1, 0]], dtype=np.int8))
    >>> start.tolist(), end.tolist(), sign.tolist()
    ([1, 3, 5], [3, 4, 6], [1, -1, 1])
    """
    width = steps.shape[1]
    flat = steps.ravel()
    idx = np.flatnonzero(flat)
    if idx.size == 0:
        empty = np.zeros(0, dtype=np.intp)
        return empty, empty, empty, empty
    value = flat[idx]
    cut = (np.diff(idx) != 1) | (np.diff(value) != 0)
    first = np.concatenate(([True], cut))
    last = np.concatenate((cut, [True]))
    line, start = np.divmod(idx[first], width)
    end = idx[last] + 1 - line * width
    return line, start, end, value[first].astype(np.intp)


def _edge_steps(low: NDArray[np.int8], high: NDArray[np.int8]) -> NDArray[np.int8]:
    """Return ``high - low`` with a zero separator column appended (see :func:`_runs`)."""
    out = np.zeros((low.shape[0], low.shape[1] + 1), dtype=np.int8)
    np.subtract(high, low, out=out[:, :-1])
    return out


def _horizontal(padded: NDArray[np.int8]) -> FloatArray:
    """Horizontal segments (on lines y = const) of a padded int8 grid.

    A segment is directed so that the occupied cell lies on the side of the normal
    ``(-(y1 - y0), x1 - x0)``: +x when the occupied cell is below (larger y).
    """
    steps = _edge_steps(padded[:-1, 1:-1], padded[1:, 1:-1])  # line y=i, edge x in [j, j+1)
    y, start, end, sign = _runs(steps)
    x0 = np.where(sign > 0, start, end)
    x1 = np.where(sign > 0, end, start)
    return np.column_stack((x0, y, x1, y)).astype(np.float64)


def _vertical(padded: NDArray[np.int8]) -> FloatArray:
    """Vertical segments (on lines x = const), directed like :func:`_horizontal`."""
    transposed = padded.T
    steps = _edge_steps(transposed[:-1, 1:-1], transposed[1:, 1:-1])  # line x=j, y in [i, i+1)
    x, start, end, sign = _runs(steps)
    y0 = np.where(sign > 0, end, start)
    y1 = np.where(sign > 0, start, end)
    return np.column_stack((x, y0, x, y1)).astype(np.float64)


def _check_grid(occupied: ArrayLike) -> BoolGrid:
    """Return ``occupied`` as a non-empty 2-D bool array or raise ``ValueError``."""
    grid = np.asarray(occupied, dtype=np.bool_)
    if grid.ndim != 2 or grid.size == 0:
        raise ValueError(f"occupancy grid must be a non-empty 2-D array, got shape {grid.shape}")
    return grid


def wall_segments(occupied: BoolGrid) -> FloatArray:
    """Convert an occupancy grid into exact, merged wall segments.

    Every unit edge between an occupied cell (or the outside of the grid) and a free
    cell is covered by exactly one segment; nothing else is. Collinear neighbouring
    edges whose occupied side is the same are merged. Each segment is directed so that
    the occupied cell lies on the side of the normal ``(-(y1 - y0), x1 - x0)`` (that is,
    obstacles are traced clockwise on screen, where y grows downwards).

    Args:
        occupied: ``(rows, cols)`` bool grid, True = obstacle.

    Returns:
        ``(n, 4)`` float64 array of rows ``(x0, y0, x1, y1)`` in cells: first the
        horizontal segments sorted by (y, x), then the vertical ones sorted by (x, y).

    >>> wall_segments(np.array([[False, False]])).tolist()
    [[2.0, 0.0, 0.0, 0.0], [0.0, 1.0, 2.0, 1.0], [0.0, 0.0, 0.0, 1.0], [2.0, 1.0, 2.0, 0.0]]
    """
    grid = _check_grid(occupied)
    padded = np.pad(grid, 1, constant_values=True).view(np.int8)
    return np.concatenate((_horizontal(padded), _vertical(padded)))


def padded_kinds(occupied: BoolGrid) -> KindGrid:
    """The kinds grid of a world without movable obstacles: 1 on walls and on a border ring.

    Cell (r, c) is at ``[r + 1, c + 1]``; the ring stands for the outside of the map,
    which counts as a static wall.
    """
    return np.pad(_check_grid(occupied), 1, constant_values=True).astype(np.int8)


def _kind_steps(low: KindArray, high: KindArray) -> KindArray:
    """Signed kind of every unit edge between ``low`` and ``high`` cells (see :func:`_runs`).

    ``+k`` where only the ``high`` cell is occupied (kind ``k``), ``-k`` where only the
    ``low`` one is, 0 between two free or two occupied cells; for kinds 0/1 this is
    ``high - low``, as :func:`_edge_steps` computes it.
    """
    out = np.zeros((low.shape[0], low.shape[1] + 1), dtype=np.int8)
    np.subtract(high * (low == 0), low * (high == 0), out=out[:, :-1])
    return out


def edge_segments(
    kinds: KindGrid, axis: int, lines: tuple[int, int], span: tuple[int, int]
) -> tuple[FloatArray, KindArray]:
    """Merged wall segments on a window of grid lines, with the kind of their occupied side.

    Args:
        kinds: padded kinds grid (see :func:`padded_kinds`).
        axis: 0 for the horizontal lines ``y = line`` (edges along x), 1 for the vertical
            lines ``x = line`` (edges along y).
        lines: first and last line, both included (0 .. rows for horizontal lines).
        span: the unit edges ``span[0] .. span[1] - 1`` along each line.

    Returns:
        ``(n, 4)`` segments directed as :func:`wall_segments` directs them (horizontal ones
        sorted by (y, x), vertical ones by (x, y)) and the ``(n,)`` int8 kind of each.
        A run stops at the window's ends, so a caller must widen ``span`` until no
        boundary edge continues a run past it.

    >>> kinds = padded_kinds(np.array([[False, False]]))
    >>> edge_segments(kinds, 0, (0, 1), (0, 2))[0].tolist()
    [[2.0, 0.0, 0.0, 0.0], [0.0, 1.0, 2.0, 1.0]]
    """
    grid = kinds if axis == 0 else kinds.T
    (first, last), (lo, hi) = lines, span
    steps = _kind_steps(
        grid[first : last + 1, lo + 1 : hi + 1], grid[first + 1 : last + 2, lo + 1 : hi + 1]
    )
    line, start, end, value = _runs(steps)
    line, start, end = line + first, start + lo, end + lo
    forward = value > 0
    if axis == 0:
        x0, x1 = np.where(forward, start, end), np.where(forward, end, start)
        segments = np.column_stack((x0, line, x1, line))
    else:
        y0, y1 = np.where(forward, end, start), np.where(forward, start, end)
        segments = np.column_stack((line, y0, line, y1))
    return segments.astype(np.float64), np.abs(value).astype(np.int8)


def seed_cells(seeds_xy: ArrayLike, shape: tuple[int, int]) -> NDArray[np.intp]:
    """Convert world seed points ``(x, y)`` into ``(n, 2)`` (row, col) cells, checked in range."""
    points = np.asarray(seeds_xy, dtype=np.float64).reshape(-1, 2)
    cells = np.floor(points[:, ::-1]).astype(np.intp)
    inside = (cells >= 0).all(axis=1) & (cells < np.array(shape)).all(axis=1)
    if not inside.all():
        x, y = points[np.argmin(inside)]
        raise MapError(
            f"Start point (x={x:g}, y={y:g}) lies outside the map of {shape[1]} x {shape[0]} "
            "cells (x = column, y = row). Choose start positions inside the map."
        )
    return cells


def free_components_mask(occupied: BoolGrid, seeds_xy: ArrayLike) -> BoolGrid:
    """Return the free cells 4-connected to any of the seed points.

    Diagonal steps are not connections, so two obstacles touching at a corner close the
    passage (as they do for rays and for a robot of any size).

    Args:
        occupied: ``(rows, cols)`` bool grid, True = obstacle.
        seeds_xy: one point ``(x, y)`` or an ``(n, 2)`` array of points, in cells.

    Returns:
        Bool grid of the same shape, True on the reachable free cells.

    Raises:
        MapError: a seed lies outside the grid or on an obstacle cell.

    >>> grid = np.array([[False, True, False]])
    >>> free_components_mask(grid, (0.5, 0.5)).tolist()
    [[True, False, False]]
    """
    grid = _check_grid(occupied)
    cells = seed_cells(seeds_xy, grid.shape)
    blocked = grid[cells[:, 0], cells[:, 1]]
    if blocked.any():
        row, col = cells[np.argmax(blocked)]
        raise MapError(
            f"Start point in cell (x={col}, y={row}) is on an obstacle. "
            "Choose start positions on free cells of the map."
        )
    return connected_to(~grid, cells)


def connected_to(free: BoolGrid, cells: NDArray[np.intp]) -> BoolGrid:
    """The cells of ``free`` 4-connected to any of ``cells`` (``(n, 2)`` row, col; a cell
    that is not free joins nothing).

    >>> connected_to(np.array([[True, False, True]]), np.array([[0, 2]])).tolist()
    [[False, False, True]]
    """
    labels, _ = ndimage.label(free, structure=FOUR_CONNECTED)
    ids = np.unique(labels[cells[:, 0], cells[:, 1]])
    return np.isin(labels, ids[ids > 0])
