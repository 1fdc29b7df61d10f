"""World (phase 1, geometry): the pymunk Space holding the true walls and robot bodies.

The ground-truth grid becomes static pymunk segments lying exactly on the
boundary between occupied and free cells (``maps.wall_segments``); robots are
kinematic bodies with circle shapes. Swept circles (motion checks) are pymunk
segment queries; scans (sensing, line of sight) are one compiled traversal of the
truth grid (``world/raycast.py``), exact because the segments lie on its cell
boundaries. Only :class:`World` (through
the :class:`~mresim_phys.world.wallset.WallSet` it owns) mutates the Space:
:meth:`World.place_robots`, once per step, after every robot has moved, and the
changes of the world below.

A world can change (``world/changes.py``): :meth:`World.set_cells` turns cells
into walls or free space, and movable obstacles (:meth:`World.add_movable`,
:meth:`World.move_movable`, :meth:`World.remove_movable`) are footprints of whole
cells. Every change writes the truth grid in place (``occupied`` stays the array
renderers and snapshots hold), bumps :attr:`World.version` and returns a
:class:`~mresim_phys.world.changes.Change`. A change of walls rebuilds only the wall
segments around the cells that changed (``world/wallset.py``), so the static body
always holds exactly the segments ``maps.wall_segments`` builds from the static
layer. Each movable obstacle is a kinematic body of its own carrying its footprint's
outline (``world/bodies.py``): moving it moves the body, no wall segment is touched.
Its segments have their own category, which every obstacle filter includes: line of
sight and motion meet it exactly where the grid has it.

Segment and swept-circle queries go through :class:`~mresim_phys.world.queries.SpaceQuery`
(Chipmunk's C function via pymunk's cffi handle, one reused result struct, one query at a
time; docs/performance.md, Kernels). Walls live in the
default bounding-box tree, inserted in a fixed shuffled order (sorted insertion
builds a degenerate tree). The spatial hash, measured as fast, is NOT
used: its segment query misses hits near the end of a ray (a ray from (60, 30)
to (1.88, 44.90) passes through the wall x = 2 with ``use_spatial_hash(10, n)``;
tests/test_sensing.py keeps that case).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cached_property
from types import MappingProxyType

import numpy as np
import pymunk
from numpy.typing import ArrayLike

from mresim_phys.types import BoolGrid, FloatArray
from mresim_phys.world.bodies import MovableBodies
from mresim_phys.world.changes import (
    Change,
    Layers,
    Movable,
    cells_of,
    check_box,
    circles_on_cells,
    join_boxes,
)
from mresim_phys.world.clearance import box_clear
from mresim_phys.world.maps import wall_segments
from mresim_phys.world.queries import ALL_BITS, Hit, QueryFilter, SpaceQuery
from mresim_phys.world.raycast import cast_fan
from mresim_phys.world.wallset import (
    MOVABLE_CATEGORY,
    OBSTACLE_CATEGORIES,
    QUIET_CATEGORY,
    RADIO_CATEGORIES,
    ROBOT_CATEGORY,
    SHUFFLE_SEED,
    WALL_CATEGORY,
    Box,
    WallSet,
)

__all__ = [
    "MOVABLE_CATEGORY",
    "ROBOT_CATEGORY",
    "SHUFFLE_SEED",
    "WALL_CATEGORY",
    "Box",
    "Change",
    "Hit",
    "Movable",
    "Scan",
    "World",
]

NO_CIRCLES = np.zeros((0, 3))
# cells: a moving circle that only grazes a shape (passes it at exactly its radius, as a
# path along cells next to a wall corner does when radius + wall_margin < radius + 0.71)
# touches without entering it; such a move is not blocked, or a robot would bump at the
# same corner on every replan and never move again
GRAZE = 1e-6

Point = tuple[float, float]


@dataclass(frozen=True)
class Scan:
    """One laser scan: ranges per ray, their world angles, and the hit surfaces."""

    origin: tuple[float, float]
    angles: FloatArray  # world angle of every ray, radians
    ranges: FloatArray  # distance to the first hit, or max range
    normals: FloatArray  # (n, 2) surface normal at the hit, zeros where nothing was hit
    wall_hit: np.ndarray  # bool (n,): the ray ended on a wall below max range
    max_range: float

    @cached_property
    def dirs(self) -> FloatArray:
        """Unit direction (n, 2) of every ray."""
        return np.column_stack((np.cos(self.angles), np.sin(self.angles)))

    @cached_property
    def ends(self) -> FloatArray:
        """End point (n, 2) of every ray: the hit, or the point at max range."""
        return np.asarray(self.origin) + self.ranges[:, None] * self.dirs

    @cached_property
    def on_wall(self) -> np.ndarray:
        """Rays (bool, n) that ended on a wall below max range."""
        return self.wall_hit & (self.ranges < self.max_range)


class World:
    """The true environment: occupancy grid, wall segments and robot bodies in one Space."""

    def __init__(self, occupied: BoolGrid, robot_radii: list[float]) -> None:
        self.occupied = occupied  # the truth; changes write it in place
        self.space = pymunk.Space(threaded=False)
        self._walls = WallSet(self.space, wall_segments(occupied))
        self.bodies = [self._add_robot(i, r) for i, r in enumerate(robot_radii)]
        self._radii = np.asarray(robot_radii, dtype=np.float64)
        self._robot_xy = self._body_positions()
        self._circles: dict[int, FloatArray] = {}  # blocking circles by query group, this step
        self._query = SpaceQuery(self.space)
        self.version = 0  # bumped by every change of the truth after step 0
        self._layers: Layers | None = None  # built by the first change
        self._movables: dict[str, Movable] = {}
        self._movable_bodies = MovableBodies(self.space)
        self._debris: tuple[int, BoolGrid, BoolGrid] | None = None  # cache of debris()

    @property
    def shape(self) -> tuple[int, int]:
        """(rows, cols) of the map."""
        rows, cols = self.occupied.shape
        return rows, cols

    @property
    def segments(self) -> FloatArray:
        """``(n, 4)`` wall segments now in the Space (``maps.wall_segments``'s rows until
        the first change)."""
        return self._walls.segments

    @property
    def movables(self) -> Mapping[str, Movable]:
        """The movable obstacles by name (read-only)."""
        return MappingProxyType(self._movables)

    def set_cells(self, box: Box, occupied: ArrayLike) -> Change:
        """Make the cells of ``box`` walls (True) or free (False): a bool, or a bool array
        of the box's shape. This sets the static layer: a movable obstacle standing on a
        cleared cell keeps it occupied."""
        box = check_box(box, self.shape)
        self._truth_layers().set_static(box, cells_of(occupied, box))
        return self._commit([box])

    def set_region(self, cells: BoolGrid, occupied: bool) -> Change:
        """Make the True cells of the map-sized mask ``cells`` walls (rubble) or free,
        leaving the other cells of their bounding box as they are."""
        rows, cols = np.flatnonzero(cells.any(axis=1)), np.flatnonzero(cells.any(axis=0))
        if len(rows) == 0:
            return Change(self.version)
        box = (int(rows[0]), int(rows[-1]) + 1, int(cols[0]), int(cols[-1]) + 1)
        window = (slice(box[0], box[1]), slice(box[2], box[3]))
        static = self._truth_layers().static[window]
        return self.set_cells(box, static | cells[window] if occupied else static & ~cells[window])

    def add_movable(
        self,
        name: str,
        footprint: BoolGrid | tuple[int, int],
        at: tuple[int, int],
        blocks_radio: bool = True,
    ) -> Change:
        """Put a movable obstacle called ``name`` on the map: ``footprint`` is a bool mask
        or (height, width) of a solid box, ``at`` the (row, col) of its top-left cell;
        with ``blocks_radio`` false, line of sight and path loss pass through it."""
        if name in self._movables:
            raise ValueError(f"a movable obstacle called {name!r} is already on the map")
        movable = Movable.make(name, footprint, at, self.shape, blocks_radio)
        self._truth_layers().add_cover(movable, +1)
        self._movables[name] = movable
        self._movable_bodies.add(movable)
        return self._commit([movable.box])

    def move_movable(
        self, name: str, at: tuple[int, int], footprint: BoolGrid | tuple[int, int] | None = None
    ) -> Change:
        """Move ``name`` so its top-left cell is ``at`` (whole cells), optionally with a new
        footprint (a door leaf swinging from one position to the next)."""
        old = self._movable(name)
        cells = old.footprint if footprint is None else footprint
        new = Movable.make(name, cells, at, self.shape, old.blocks_radio)
        layers = self._truth_layers()
        layers.add_cover(old, -1)
        layers.add_cover(new, +1)
        self._movables[name] = new
        self._movable_bodies.move(new)
        return self._commit(join_boxes(old.box, new.box))

    def remove_movable(self, name: str) -> Change:
        """Take ``name`` off the map."""
        old = self._movable(name)
        self._truth_layers().add_cover(old, -1)
        del self._movables[name]
        self._movable_bodies.remove(name)
        return self._commit([old.box])

    def fits(
        self,
        footprint: BoolGrid,
        at: tuple[int, int],
        robots: FloatArray,
        moving: str | None = None,
        over_walls: bool = False,
    ) -> bool:
        """Whether ``footprint`` with its top-left cell at ``at`` lies on the map clear of
        the robots' bodies (``robots``: rows of x, y, radius), of every movable obstacle
        but ``moving`` (the one being moved) and, unless ``over_walls``, of the static
        walls and rubble."""
        own = self._movables.get(moving) if moving is not None else None
        circles = np.ascontiguousarray(robots, dtype=np.float64)
        return self._truth_layers().clear(footprint, at, own, over_walls, circles)

    @property
    def radio_occupied(self) -> BoolGrid:
        """The truth grid as radio meets it: without the movable obstacles that do not
        block radio (the truth grid itself while there are none)."""
        layers = self._layers
        return self.occupied if layers is None or layers.radio is None else layers.radio

    @property
    def original(self) -> BoolGrid:
        """The map's walls before any change of the world (read-only)."""
        layers = self._layers
        grid = self.occupied if layers is None else layers.original
        view: BoolGrid = grid.view()
        view.flags.writeable = False
        return view

    def debris(self) -> tuple[BoolGrid, BoolGrid] | None:
        """(rubble, gave_way): static cells free on the original map, and free cells that
        were its walls (new read-only grids, kept until the static layer changes again);
        None while the static layer is the original map's."""
        layers = self._layers
        if layers is None or layers.static_changes == 0:
            return None
        if self._debris is None or self._debris[0] != layers.static_changes:
            rubble = layers.static & ~layers.original
            gave_way = layers.original & ~layers.static
            rubble.flags.writeable = gave_way.flags.writeable = False
            self._debris = (layers.static_changes, rubble, gave_way)
        return self._debris[1], self._debris[2]

    def radio_filter(self) -> QueryFilter:
        """The Chipmunk filter of what blocks radio: walls and radio-blocking movables."""
        return (0, ALL_BITS, RADIO_CATEGORIES)

    def _movable(self, name: str) -> Movable:
        if name not in self._movables:
            known = ", ".join(sorted(self._movables)) or "none"
            raise KeyError(f"no movable obstacle called {name!r} (on the map: {known})")
        return self._movables[name]

    def _truth_layers(self) -> Layers:
        if self._layers is None:
            self._layers = Layers(self.occupied)
        return self._layers

    def _commit(self, boxes: list[Box]) -> Change:
        """Fold the changed layers of ``boxes`` into the truth and the Space."""
        layers = self._truth_layers()
        patches = []
        for box in boxes:
            rebuild, patch = layers.refresh(box)
            if rebuild is not None:
                self._walls.rebuild(layers.kinds, rebuild)
            if patch is not None:
                patches.append(patch)
        if not patches:
            return Change(self.version)
        self.version += 1
        centres = self._robot_xy  # where place_robots last stood the bodies
        hit = {int(i) for p in patches for i in circles_on_cells(centres, self._radii, p)}
        return Change(self.version, tuple(patches), tuple(sorted(hit)))

    def buried(self, position: Point) -> bool:
        """Whether ``position`` lies in an occupied cell (or off the map)."""
        rows, cols = self.shape
        row, col = math.floor(position[1]), math.floor(position[0])
        return not (0 <= row < rows and 0 <= col < cols) or bool(self.occupied[row, col])

    def _add_robot(self, index: int, radius: float) -> pymunk.Body:
        body = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        shape = pymunk.Circle(body, radius)
        shape.filter = pymunk.ShapeFilter(group=index + 1, categories=ROBOT_CATEGORY)
        body.position = (-1e6 - 10 * index, -1e6)  # parked off-map until placed
        self.space.add(body, shape)
        return body

    def place_robots(self, positions: list[tuple[float, float]]) -> None:
        """Move every robot body to its position (the one per-step mutation of the Space)."""
        for body, position in zip(self.bodies, positions, strict=True):
            body.position = position
            self.space.reindex_shapes_for_body(body)
        self._robot_xy = self._body_positions()
        self._circles = {}

    def _body_positions(self) -> FloatArray:
        """(n, 2) positions of the robot bodies, for the scan kernel's blocking circles."""
        return np.array([tuple(b.position) for b in self.bodies], dtype=np.float64).reshape(-1, 2)

    def query_filter(self, robot_index: int | None, robots_block: bool) -> QueryFilter:
        """The Chipmunk filter for queries by ``robot_index``: walls and movable obstacles
        (always: the truth grid holds both), plus other robots if they block."""
        mask = OBSTACLE_CATEGORIES | (ROBOT_CATEGORY if robots_block else 0)
        group = 0 if robot_index is None else robot_index + 1
        return (group, ALL_BITS, mask)

    def first_hit(
        self,
        start: Point,
        end: Point,
        radius: float,
        shape_filter: QueryFilter,
    ) -> Hit | None:
        """The first shape a segment (swept by ``radius``) from ``start`` to ``end`` touches
        (:class:`~mresim_phys.world.queries.SpaceQuery`; safe from several threads)."""
        return self._query.first_hit(start, end, radius, shape_filter)

    def cast_rays(
        self,
        origin: Point,
        angles: FloatArray,
        max_range: float,
        shape_filter: QueryFilter,
    ) -> Scan:
        """Cast one ray per angle from ``origin``; exact distance to the first hit.

        One compiled call (``world/raycast.py``): a traversal of the truth grid, whose
        cell boundaries are exactly the Space's wall segments, plus the robot circles
        the filter lets block (every robot but the filter's group). A filter without
        the radio-quiet obstacles' category (:meth:`radio_filter`) traverses the grid
        radio meets (:attr:`radio_occupied`).
        """
        n = len(angles)
        ranges, normals, wall_hit = np.empty(n), np.empty((n, 2)), np.empty(n, dtype=np.bool_)
        grid, circles = self.ray_targets(shape_filter)
        cast_fan(
            grid,
            float(origin[0]),
            float(origin[1]),
            np.ascontiguousarray(angles, dtype=np.float64),
            float(max_range),
            circles,
            ranges,
            normals,
            wall_hit,
        )
        return Scan(origin, angles, ranges, normals, wall_hit, max_range)

    def ray_targets(self, shape_filter: QueryFilter) -> tuple[BoolGrid, FloatArray]:
        """What rays cast with ``shape_filter`` stop at: the grid they traverse and the
        (k, 3) robot circles (x, y, radius) that block them (``cast_fan``'s inputs)."""
        quiet_blocks = shape_filter[2] & QUIET_CATEGORY
        grid = self.occupied if quiet_blocks else self.radio_occupied
        return grid, self._blocking_circles(shape_filter)

    def _blocking_circles(self, shape_filter: QueryFilter) -> FloatArray:
        """(k, 3) rows (x, y, radius) of the robot bodies ``shape_filter`` collides with."""
        group, _, mask = shape_filter
        if not mask & ROBOT_CATEGORY or not self.bodies:
            return NO_CIRCLES
        circles = self._circles.get(group)
        if circles is None:  # once per robot and step: every scan and move of it asks
            keep = np.arange(len(self.bodies)) != group - 1  # its own body never blocks
            circles = np.column_stack((self._robot_xy, self._radii))[keep]
            self._circles[group] = circles
        return circles

    def blocked(
        self,
        start: Point,
        end: Point,
        radius: float,
        shape_filter: QueryFilter,
    ) -> Hit | None:
        """The obstacle a circle of ``radius`` moving from ``start`` to ``end`` would hit.

        A contact the circle is moving away from (normal along the motion) does not
        block, so a robot grazing a wall can always back off, also when a change of the
        world put an obstacle into its body. A circle whose centre lies in an occupied
        cell (buried by a change) cannot move at all: every move is blocked where it is.
        """
        if self.buried(start):
            return Hit(start, (0.0, 0.0), 0.0, True)
        grid, circles = self.ray_targets(shape_filter)  # every shape the filter can hit
        x0, x1 = min(start[0], end[0]) - radius, max(start[0], end[0]) + radius
        y0, y1 = min(start[1], end[1]) - radius, max(start[1], end[1]) + radius
        if box_clear(grid, circles, x0, y0, x1, y1):  # no shape near: Chipmunk finds none
            return None
        hit = self.first_hit(start, end, max(radius - GRAZE, 0.0), shape_filter)
        if hit is None:
            return None
        dx, dy = end[0] - start[0], end[1] - start[1]
        if hit.alpha <= 1e-9 and hit.normal[0] * dx + hit.normal[1] * dy >= 0:
            return None
        return hit

    def overlaps_wall(self, position: tuple[float, float], radius: float) -> bool:
        """True if a circle at ``position`` touches a wall or leaves the map."""
        rows, cols = self.shape
        x, y = position
        if not (radius <= x <= cols - radius and radius <= y <= rows - radius):
            return True
        hit = self.first_hit(position, position, radius, (0, ALL_BITS, OBSTACLE_CATEGORIES))
        return hit is not None or bool(self.occupied[int(y), int(x)])
