"""World (phase 1, geometry): each movable obstacle as one kinematic body in the Space.

A movable obstacle (a moving obstacle, a closed door) is a footprint of whole cells
at a whole-cell offset (``world/changes.py``). Its body carries the footprint's
outline, merged axis-aligned segments in the footprint's own cell coordinates
(:func:`outline`), and stands at ``(col, row)`` of the footprint's top-left cell, so
every segment lies exactly on a cell boundary of the truth grid, as the static
walls do (a body at angle 0 adds its integer offset to integer end points: exact in
floating point). Moving the obstacle moves the body and re-indexes its few shapes;
no wall segment of the map is touched (the static :class:`~mresim_phys.world.wallset.WallSet`
follows only walls and rubble). Where an obstacle touches a wall or another
obstacle, both outlines lie on the shared boundary; where a door's ends lie inside
walls, the part of its outline there is inside the wall. Neither changes what a
query from free space meets first.
"""

from __future__ import annotations

import numpy as np
import pymunk

from mresim_phys.types import BoolGrid, FloatArray
from mresim_phys.world.changes import Movable
from mresim_phys.world.maps import edge_segments
from mresim_phys.world.wallset import MOVABLE_CATEGORY, QUIET_CATEGORY


def outline(footprint: BoolGrid) -> FloatArray:
    """``(n, 4)`` merged boundary segments of a footprint (cells outside it are free),
    in its own coordinates: cell (r, c) covers [c, c + 1] x [r, r + 1]."""
    kinds = np.pad(footprint, 1).astype(np.int8)
    rows, cols = footprint.shape
    horizontal, _ = edge_segments(kinds, 0, (0, rows), (0, cols))
    vertical, _ = edge_segments(kinds, 1, (0, cols), (0, rows))
    return np.concatenate((horizontal, vertical))


class MovableBodies:
    """The kinematic bodies of the movable obstacles on the map, by name."""

    def __init__(self, space: pymunk.Space) -> None:
        self._space = space
        self._bodies: dict[str, tuple[pymunk.Body, list[pymunk.Segment], Movable]] = {}

    def add(self, movable: Movable) -> None:
        """Put ``movable``'s body into the Space."""
        body = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        body.position = (movable.col, movable.row)
        shapes = self._shapes(body, movable)
        self._space.add(body, *shapes)
        self._bodies[movable.name] = (body, shapes, movable)

    def move(self, movable: Movable) -> None:
        """Stand ``movable``'s body at its new place (a new footprint: new shapes)."""
        body, shapes, old = self._bodies[movable.name]
        body.position = (movable.col, movable.row)
        if old.footprint is not movable.footprint and not np.array_equal(
            old.footprint, movable.footprint
        ):
            self._space.remove(*shapes)
            shapes = self._shapes(body, movable)
            self._space.add(*shapes)
        else:
            self._space.reindex_shapes_for_body(body)
        self._bodies[movable.name] = (body, shapes, movable)

    def remove(self, name: str) -> None:
        """Take ``name``'s body out of the Space."""
        body, shapes, _ = self._bodies.pop(name)
        self._space.remove(body, *shapes)

    @staticmethod
    def _shapes(body: pymunk.Body, movable: Movable) -> list[pymunk.Segment]:
        category = MOVABLE_CATEGORY if movable.blocks_radio else QUIET_CATEGORY
        shapes = []
        for x0, y0, x1, y1 in outline(movable.footprint).tolist():
            shape = pymunk.Segment(body, (x0, y0), (x1, y1), 0.0)
            shape.filter = pymunk.ShapeFilter(categories=category)
            shapes.append(shape)
        return shapes
