"""World (phase 1, geometry): the layers a changing truth is made of, and what a change reports.

The truth grid is ``static | movable footprints``: the static layer holds walls and
rubble (changed by ``World.set_cells``), and every movable obstacle adds its
footprint, a set of whole cells at a whole-cell offset, to a cover count (so
footprints may overlap each other and the walls). :class:`Layers` keeps both and a
padded *kinds* grid of the static layer (0 free, 1 wall; ``maps.edge_segments``), and
:meth:`Layers.refresh` folds a window of them into the truth grid in place, reporting
which cells' truth flipped (a :class:`Patch`) and which static cells changed (the
window whose wall segments must be rebuilt). Movable obstacles have no wall segments
of the map: each is a body of its own in the Space (``world/bodies.py``).

A :class:`Change` is what every mutation of the world returns: the world's new
version, the patches of flipped cells, and the robots whose bodies now overlap a
newly occupied cell. Callers use it to retarget coverage and to log the truth.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numba import njit
from numpy.typing import ArrayLike

from mresim_phys.types import BoolGrid, FloatArray, IntArray
from mresim_phys.world.layerkernels import fold_truth, footprint_clear
from mresim_phys.world.maps import KindGrid, padded_kinds
from mresim_phys.world.wallset import Box

NO_CELLS = np.zeros((0, 0), dtype=bool)  # no footprint, no radio grid (kernel arguments)


def check_box(box: Box, shape: tuple[int, int]) -> Box:
    """``box`` as ints if it is a non-empty window inside a map of ``shape``, else ValueError."""
    row0, row1, col0, col1 = (int(v) for v in box)
    rows, cols = shape
    if not (0 <= row0 < row1 <= rows and 0 <= col0 < col1 <= cols):
        raise ValueError(
            f"box {tuple(box)} (row0, row1, col0, col1; half-open) must be a non-empty window"
            f" inside the {rows} x {cols} map"
        )
    return row0, row1, col0, col1


def cells_of(value: ArrayLike, box: Box) -> BoolGrid:
    """``value`` (a bool, or a bool array of the box's shape) as a grid of the box's shape."""
    shape = (box[1] - box[0], box[3] - box[2])
    cells = np.asarray(value)
    if cells.dtype != np.bool_:
        raise ValueError(f"cell values must be bool, got {cells.dtype}")
    if cells.ndim == 0:
        return np.full(shape, bool(cells))
    if cells.shape != shape:
        raise ValueError(f"cell values of shape {cells.shape} do not fit the box {shape}")
    return cells


def bounding_box(mask: BoolGrid, row0: int = 0, col0: int = 0) -> Box | None:
    """Smallest box holding every True cell of ``mask`` (offset by row0, col0), or None."""
    rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    if rows.size == 0:
        return None
    return (
        row0 + int(rows[0]),
        row0 + int(rows[-1]) + 1,
        col0 + int(cols[0]),
        col0 + int(cols[-1]) + 1,
    )


def join_boxes(a: Box, b: Box) -> list[Box]:
    """One box around both if they overlap or touch (their rebuilds would share edges)."""
    apart = a[1] < b[0] or b[1] < a[0] or a[3] < b[2] or b[3] < a[2]
    if apart:
        return [a, b]
    return [(min(a[0], b[0]), max(a[1], b[1]), min(a[2], b[2]), max(a[3], b[3]))]


@dataclass(frozen=True)
class Patch:
    """Cells whose truth flipped in one window: where (``flipped``) and what they are now."""

    row0: int
    col0: int
    flipped: BoolGrid  # True where the truth changed
    occupied: BoolGrid  # the truth of the whole window after the change

    @property
    def box(self) -> Box:
        """The window, (row0, row1, col0, col1)."""
        h, w = self.flipped.shape
        return self.row0, self.row0 + h, self.col0, self.col0 + w

    def cells(self) -> IntArray:
        """``(n, 2)`` (row, col) of every flipped cell."""
        cells: IntArray = np.argwhere(self.flipped) + np.array([self.row0, self.col0])
        return cells

    def closed(self) -> IntArray:
        """``(n, 2)`` (row, col) of every cell that became occupied."""
        closed = self.flipped & self.occupied
        cells: IntArray = np.argwhere(closed) + np.array([self.row0, self.col0])
        return cells


@dataclass(frozen=True)
class Change:
    """What one mutation of the world did (empty if the truth did not change)."""

    version: int  # the world's version after the change
    patches: tuple[Patch, ...] = ()
    robots: tuple[int, ...] = ()  # bodies (World's order) overlapping a newly occupied cell

    def __bool__(self) -> bool:
        return bool(self.patches)

    @property
    def count(self) -> int:
        """Number of cells whose truth flipped."""
        return sum(int(np.count_nonzero(p.flipped)) for p in self.patches)

    @property
    def box(self) -> Box | None:
        """Bounding box of every patch, or None if nothing changed."""
        return union_box(self.patches) if self.patches else None


def union_box(patches: Sequence[Patch]) -> Box:
    """Bounding box of every patch (at least one)."""
    boxes = [p.box for p in patches]
    return (
        min(b[0] for b in boxes),
        max(b[1] for b in boxes),
        min(b[2] for b in boxes),
        max(b[3] for b in boxes),
    )


@dataclass(frozen=True)
class Movable:
    """A movable obstacle: a footprint of whole cells whose top-left cell is (row, col)."""

    name: str
    footprint: BoolGrid  # read-only
    row: int
    col: int
    blocks_radio: bool = True  # False: line of sight and path loss pass through it

    @classmethod
    def make(
        cls,
        name: str,
        footprint: BoolGrid | tuple[int, int],
        at: tuple[int, int],
        shape: tuple[int, int],
        blocks_radio: bool = True,
    ) -> Movable:
        """A checked movable: ``footprint`` is a bool mask or (height, width) of a solid box."""
        if isinstance(footprint, np.ndarray) and not footprint.flags.writeable:
            cells = footprint  # an earlier Movable's (read-only) footprint: shared
        else:
            cells = np.array(footprint, copy=True)
        if isinstance(footprint, tuple):
            cells = np.ones(footprint, dtype=bool)
        if cells.dtype != np.bool_ or cells.ndim != 2 or not cells.any():
            raise ValueError(
                f"movable {name!r}: the footprint must be a 2-D bool mask with a True cell"
            )
        cells.flags.writeable = False
        row, col = int(at[0]), int(at[1])
        check_box((row, row + cells.shape[0], col, col + cells.shape[1]), shape)
        return cls(name, cells, row, col, blocks_radio)

    @property
    def box(self) -> Box:
        """The footprint's window, (row0, row1, col0, col1)."""
        h, w = self.footprint.shape
        return self.row, self.row + h, self.col, self.col + w


class Layers:
    """Static walls, movable cover counts and the kinds grid behind the truth grid."""

    def __init__(self, occupied: BoolGrid) -> None:
        self.occupied = occupied  # the world's truth grid, written in place
        self.static = occupied.copy()
        self.original = occupied.copy()  # the map before any change (views draw rubble by it)
        self.static_changes = 0  # bumped by every write of the static layer
        self.cover = np.zeros(occupied.shape, dtype=np.uint16)
        self.quiet = np.zeros(occupied.shape, dtype=np.uint16)  # cover radio passes through
        self.kinds: KindGrid = padded_kinds(occupied)
        self.radio: BoolGrid | None = None  # what radio meets, once a quiet movable exists

    def set_static(self, box: Box, cells: BoolGrid) -> None:
        """Walls (True) or free space (False) in the static layer of ``box``."""
        row0, row1, col0, col1 = box
        self.static[row0:row1, col0:col1] = cells
        self.static_changes += 1

    def add_cover(self, movable: Movable, sign: int) -> None:
        """Add (sign +1) or take away (-1) a movable's footprint from the cover count."""
        row0, row1, col0, col1 = movable.box
        windows = [self.cover[row0:row1, col0:col1]]
        if not movable.blocks_radio:
            windows.append(self.quiet[row0:row1, col0:col1])
            if self.radio is None:
                self.radio = self.occupied.copy()
        for window in windows:
            if sign > 0:
                window += movable.footprint
            else:
                window -= movable.footprint

    def clear(
        self,
        footprint: BoolGrid,
        at: tuple[int, int],
        own: Movable | None,
        over_walls: bool,
        circles: FloatArray,
    ) -> bool:
        """Whether ``footprint`` at top-left cell ``at`` lies on the map and covers no cell
        of another movable (``own``'s cells do not count), nor, unless ``over_walls``, a
        static wall, nor a circle of ``circles`` (rows x, y, radius: robots' bodies)."""
        own_cells, own_at = (NO_CELLS, (0, 0)) if own is None else (own.footprint, own.box[::2])
        return bool(
            footprint_clear(
                self.cover, self.static, footprint, int(at[0]), int(at[1]),
                own_cells, int(own_at[0]), int(own_at[1]), over_walls, circles,
            )
        )  # fmt: skip

    def refresh(self, box: Box) -> tuple[Box | None, Patch | None]:
        """Fold the layers of ``box`` into the kinds and truth grids.

        Returns the box of cells whose kind changed (their wall segments must be
        rebuilt: only the static layer has segments of the map; movables are bodies,
        ``world/bodies.py``) and the patch of cells whose truth flipped (None for
        either if there are none).
        """
        row0, row1, col0, col1 = box
        flipped = np.empty((row1 - row0, col1 - col0), dtype=bool)
        radio = NO_CELLS if self.radio is None else self.radio
        k0, k1, k2, k3, r0, r1, c0, c1 = fold_truth(
            self.static, self.cover, self.quiet, radio, self.kinds, self.occupied, flipped,
            row0, row1, col0, col1,
        )  # fmt: skip
        rebuild = None if k0 < 0 else (k0, k1, k2, k3)
        if r0 < 0:
            return rebuild, None
        local = flipped[r0 - row0 : r1 - row0, c0 - col0 : c1 - col0]
        return rebuild, Patch(r0, c0, local, self.occupied[r0:r1, c0:c1].copy())


def footprint_in(movable: Movable, box: Box) -> IntArray:
    """``movable``'s footprint cut to ``box`` (1 on the cells it covers there)."""
    row0, row1, col0, col1 = box
    out = np.zeros((row1 - row0, col1 - col0), dtype=np.intp)
    r0, r1, c0, c1 = movable.box
    a0, a1, b0, b1 = max(r0, row0), min(r1, row1), max(c0, col0), min(c1, col1)
    if a0 < a1 and b0 < b1:
        out[a0 - row0 : a1 - row0, b0 - col0 : b1 - col0] = movable.footprint[
            a0 - r0 : a1 - r0, b0 - c0 : b1 - c0
        ]
    return out


def circles_cover(centres: FloatArray, radii: FloatArray, cells: IntArray) -> BoolGrid:
    """For each circle, whether it overlaps (not just touches) one of the (row, col) ``cells``."""
    if len(cells) == 0 or len(centres) == 0:
        return np.zeros(len(centres), dtype=bool)
    row0, col0 = cells.min(axis=0)
    row1, col1 = cells.max(axis=0) + 1
    x, y, r = centres[:, 0], centres[:, 1], radii
    near = np.flatnonzero((x + r > col0) & (x - r < col1) & (y + r > row0) & (y - r < row1))
    out = np.zeros(len(centres), dtype=bool)
    if len(near):
        x, y, r = x[near, None], y[near, None], r[near, None]
        dx = np.maximum(np.maximum(cells[:, 1] - x, 0.0), x - (cells[:, 1] + 1))
        dy = np.maximum(np.maximum(cells[:, 0] - y, 0.0), y - (cells[:, 0] + 1))
        out[near] = (dx * dx + dy * dy < r * r).any(axis=1)
    return out


def circles_on_cells(centres: FloatArray, radii: FloatArray, patch: Patch) -> IntArray:
    """Indices of the circles that overlap (not just touch) a newly occupied cell of ``patch``."""
    row0, row1, col0, col1 = patch.box
    near = circles_near(centres, radii, row0, row1, col0, col1)
    if len(near) == 0:  # the usual case: no robot near the change (its cells not listed)
        return np.zeros(0, dtype=np.intp)
    x, y, r = centres[:, 0], centres[:, 1], radii
    cells = patch.closed()
    if len(cells) == 0:
        return np.zeros(0, dtype=np.intp)
    x, y, r = x[near, None], y[near, None], r[near, None]
    dx = np.maximum(np.maximum(cells[:, 1] - x, 0.0), x - (cells[:, 1] + 1))
    dy = np.maximum(np.maximum(cells[:, 0] - y, 0.0), y - (cells[:, 0] + 1))
    touching: IntArray = near[(dx * dx + dy * dy < r * r).any(axis=1)]
    return touching


@njit(cache=True, nogil=True)
def circles_near(
    centres: FloatArray, radii: FloatArray, row0: int, row1: int, col0: int, col1: int
) -> IntArray:
    """Indices of the circles whose bounding square overlaps the box (one compiled loop:
    numpy's per-call cost on a handful of robots was most of a moving obstacle's check)."""
    near = np.empty(len(radii), np.intp)
    count = 0
    for i in range(len(radii)):
        x, y, r = centres[i, 0], centres[i, 1], radii[i]
        if x + r > col0 and x - r < col1 and y + r > row0 and y - r < row1:
            near[count] = i
            count += 1
    return near[:count]
