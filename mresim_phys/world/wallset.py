"""World (phase 1, geometry): the static wall segments of the Space, kept so a window can change.

:class:`WallSet` owns every static ``pymunk.Segment`` of the world together with
its endpoints, the grid line it lies on, the unit edges it covers along that line
and the kind of its occupied side (``maps.edge_segments``; the world gives it the
static layer only, kind 1: movable obstacles are bodies of their own,
``world/bodies.py``). When cells change, :meth:`WallSet.rebuild` replaces
exactly the segments whose unit edges touch the changed cells: a segment is
run-length merged along its line, so a long wall may cross the window; the
window's span along each line is widened until no segment on those lines merely
touches it, every segment inside is removed and the span is merged again from the
grid. The result is always what a from-scratch build of the current grid gives,
merging included (``tests/test_world_changes.py`` checks it against the Space).

Construction adds the segments exactly as ``World`` always did: one shape per row of
``maps.wall_segments``, created and added in the fixed shuffled order.
"""

from __future__ import annotations

import numpy as np
import pymunk
from numpy.typing import NDArray

from mresim_phys.types import FloatArray
from mresim_phys.world.maps import KindArray, KindGrid, edge_segments

WALL_CATEGORY = 0b001
ROBOT_CATEGORY = 0b010
MOVABLE_CATEGORY = 0b100  # movable obstacles that block radio (closed doors, by default)
QUIET_CATEGORY = 0b1000  # movable obstacles radio passes through (blocks_radio: false)
MOVABLE_CATEGORIES = MOVABLE_CATEGORY | QUIET_CATEGORY
OBSTACLE_CATEGORIES = WALL_CATEGORY | MOVABLE_CATEGORIES  # what the truth grid holds
RADIO_CATEGORIES = WALL_CATEGORY | MOVABLE_CATEGORY  # what line of sight and path loss count
CATEGORY_OF_KIND = {1: WALL_CATEGORY, 2: MOVABLE_CATEGORY, 3: QUIET_CATEGORY}
SHUFFLE_SEED = 0x5EED  # fixed: segment insertion order is part of the world, not of the run

Box = tuple[int, int, int, int]  # row0, row1, col0, col1 (half-open)


class WallSet:
    """The static segments of a Space, each with its line, its unit edges and its kind."""

    def __init__(self, space: pymunk.Space, segments: FloatArray) -> None:
        self._space = space
        self._rng = np.random.default_rng(SHUFFLE_SEED)
        order = self._rng.permutation(len(segments))
        shapes = [self._shape(row, 1) for row in segments[order].tolist()]
        space.add(*shapes)
        slots = np.empty(len(segments), dtype=object)
        slots[order] = shapes
        self._set(segments, np.ones(len(segments), dtype=np.int8), slots)

    def _set(self, ends: FloatArray, kinds: KindArray, shapes: NDArray[np.object_]) -> None:
        """Store the segments and derive each one's axis, line and edge range."""
        self._ends, self._kinds, self._shapes = ends, kinds, shapes
        vertical = ends[:, 0] == ends[:, 2]
        self._axis = vertical.astype(np.int8)
        self._line = np.where(vertical, ends[:, 0], ends[:, 1])
        along = np.where(vertical[:, None], ends[:, 1::2], ends[:, 0::2])
        self._lo, self._hi = along.min(axis=1), along.max(axis=1)

    def _shape(self, row: list[float], kind: int) -> pymunk.Segment:
        """One static segment (x0, y0, x1, y1) in the category of its kind."""
        x0, y0, x1, y1 = row
        shape = pymunk.Segment(self._space.static_body, (x0, y0), (x1, y1), 0.0)
        shape.filter = pymunk.ShapeFilter(categories=CATEGORY_OF_KIND[kind])
        return shape

    def __len__(self) -> int:
        return len(self._ends)

    @property
    def segments(self) -> FloatArray:
        """``(n, 4)`` current segments: those never replaced in their original order, then
        the replacements in the order they were made."""
        ends: FloatArray = self._ends.copy()
        return ends

    @property
    def kinds(self) -> KindArray:
        """``(n,)`` kind (1 wall, 2 movable) of each row of :attr:`segments`."""
        kinds: KindArray = self._kinds.copy()
        return kinds

    def rebuild(self, kinds: KindGrid, box: Box) -> None:
        """Replace the segments on every unit edge of the cells in ``box`` from ``kinds``."""
        row0, row1, col0, col1 = box
        windows = ((0, (row0, row1), (col0, col1)), (1, (col0, col1), (row0, row1)))
        stale = np.zeros(len(self._ends), dtype=bool)
        new: list[tuple[FloatArray, KindArray]] = []
        for axis, lines, span in windows:
            touching, wide = self._touching(axis, lines, span)
            stale |= touching
            new.append(edge_segments(kinds, axis, lines, wide))
        ends = np.concatenate([e for e, _ in new])
        kinds_of = np.concatenate([k for _, k in new])
        if stale.any():
            self._space.remove(*self._shapes[stale])
        added = self._add(ends, kinds_of)
        self._set(
            np.concatenate((self._ends[~stale], ends)),
            np.concatenate((self._kinds[~stale], kinds_of)),
            np.concatenate((self._shapes[~stale], added)),
        )

    def _touching(
        self, axis: int, lines: tuple[int, int], span: tuple[int, int]
    ) -> tuple[NDArray[np.bool_], tuple[int, int]]:
        """Segments on ``lines`` that share an edge or an end with ``span``, and the span
        widened to cover them all (repeated until no further segment touches it)."""
        on_lines = (self._axis == axis) & (self._line >= lines[0]) & (self._line <= lines[1])
        lo, hi = span
        while True:
            touching = on_lines & (self._lo <= hi) & (self._hi >= lo)
            if not touching.any():
                return touching, (lo, hi)
            wide_lo = min(lo, int(self._lo[touching].min()))
            wide_hi = max(hi, int(self._hi[touching].max()))
            if (wide_lo, wide_hi) == (lo, hi):
                return touching, (lo, hi)
            lo, hi = wide_lo, wide_hi

    def _add(self, ends: FloatArray, kinds: KindArray) -> NDArray[np.object_]:
        """Create and add shapes for ``ends`` (in a shuffled order: sorted insertion
        degrades the Space's tree); return them in the order of ``ends``."""
        shapes = np.empty(len(ends), dtype=object)
        if len(ends) == 0:
            return shapes
        order = self._rng.permutation(len(ends))
        made = [
            self._shape(row, kind)
            for row, kind in zip(ends[order].tolist(), kinds[order].tolist(), strict=True)
        ]
        self._space.add(*made)
        shapes[order] = made
        return shapes
