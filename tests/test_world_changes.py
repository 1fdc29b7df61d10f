"""A world that changes: set_cells and movable obstacles keep the grid and the Space in agreement.

The stateful property test drives a World through random sequences of cell changes and
movable obstacles against a plain numpy model, and after every step checks that the truth
grid is the model's, that the Space holds the static layer's ``wall_segments`` (maximally
merged) plus each movable obstacle's outline on its own body, where the model has it, so
that together they cover every boundary edge of the truth and only such edges, that rays cast
(the scan kernel and a Chipmunk query of the Space) stop where a grid traversal of
``world.occupied`` stops, that each Change
reports exactly the flipped cells and the overlapped robots, and that the reachable set
followed across the changes equals a full labelling.
"""

from __future__ import annotations

import math

import numpy as np
import pymunk
from hypothesis import settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from hypothesis.stateful import RuleBasedStateMachine, initialize, invariant, precondition, rule
from numpy.typing import NDArray
from scipy import ndimage

from mresim_phys.world.changes import Change
from mresim_phys.world.maps import wall_segments
from mresim_phys.world.reach import Reachable
from mresim_phys.world.space import MOVABLE_CATEGORY, WALL_CATEGORY, World

Grid = NDArray[np.bool_]
Edge = tuple[float, float, float, float]
VERTEX_TOL = 1e-9
RAY_TOL = 1e-6
ROBOT_RADIUS = 0.7


def unit_edges(segments: list[Edge] | NDArray[np.float64]) -> list[Edge]:
    """Every directed unit edge of axis-aligned integer segments."""
    out = []
    for x0, y0, x1, y1 in np.asarray(segments, dtype=np.float64).reshape(-1, 4).tolist():
        n = round(abs(x1 - x0) + abs(y1 - y0))
        dx, dy = (x1 - x0) / n, (y1 - y0) / n
        out += [(x0 + k * dx, y0 + k * dy, x0 + (k + 1) * dx, y0 + (k + 1) * dy) for k in range(n)]
    return out


def space_segments(world: World) -> list[tuple[Edge, int, bool]]:
    """The segments in the world's pymunk Space in world coordinates, with their collision
    categories and whether they belong to the static body (the map's walls)."""
    out = []
    for s in world.space.shapes:
        if isinstance(s, pymunk.Segment):
            a, b = s.body.local_to_world(s.a), s.body.local_to_world(s.b)
            on_static = s.body is world.space.static_body
            out.append(((a.x, a.y, b.x, b.y), s.filter.categories, on_static))
    return out


def occupied_side(edge: Edge) -> tuple[int, int]:
    """(row, col) of the cell on the normal side of a directed unit edge (may be off-map)."""
    x0, y0, x1, y1 = edge
    nx, ny = -(y1 - y0), x1 - x0
    return math.floor((y0 + y1) / 2 + 0.5 * ny), math.floor((x0 + x1) / 2 + 0.5 * nx)


def dda_first_hit(grid: Grid, x: float, y: float, dx: float, dy: float) -> tuple[float, bool]:
    """Grid traversal: distance to the first occupied (or off-map) cell, and a near-vertex flag."""
    rows, cols = grid.shape
    col, row = math.floor(x), math.floor(y)
    step_x, step_y = (1 if dx > 0 else -1), (1 if dy > 0 else -1)
    t_x = ((col + (dx > 0) - x) / dx) if dx else math.inf
    t_y = ((row + (dy > 0) - y) / dy) if dy else math.inf
    delta_x, delta_y = (abs(1 / dx) if dx else math.inf), (abs(1 / dy) if dy else math.inf)
    near_vertex = False
    while True:
        near_vertex |= abs(t_x - t_y) < VERTEX_TOL
        if t_x < t_y:
            col, t, t_x = col + step_x, t_x, t_x + delta_x
        else:
            row, t, t_y = row + step_y, t_y, t_y + delta_y
        if not (0 <= row < rows and 0 <= col < cols) or grid[row, col]:
            return t, near_vertex


def circle_overlaps_cell(x: float, y: float, radius: float, row: int, col: int) -> bool:
    dx = max(col - x, 0.0, x - (col + 1))
    dy = max(row - y, 0.0, y - (row + 1))
    return dx * dx + dy * dy < radius * radius


grids = arrays(np.bool_, st.tuples(st.integers(3, 10), st.integers(3, 10)), elements=st.booleans())
footprints = arrays(
    np.bool_, st.tuples(st.integers(1, 3), st.integers(1, 3)), elements=st.booleans()
)


class ChangingWorld(RuleBasedStateMachine):
    """A World under random changes, next to a numpy model of its layers."""

    @initialize(grid=grids, robot=st.tuples(st.floats(0, 1), st.floats(0, 1)))
    def start(self, grid: Grid, robot: tuple[float, float]) -> None:
        grid = grid.copy()
        grid[0, 0] = False  # the seed of the reachable set
        self.static = grid.copy()
        self.movables: dict[str, tuple[Grid, int, int]] = {}
        self.world = World(grid, [ROBOT_RADIUS])
        rows, cols = grid.shape
        self.robot = (robot[0] * cols, robot[1] * rows)
        self.world.place_robots([self.robot])
        self.reachable = Reachable(self.world.occupied, [(0.5, 0.5)])
        self.pending: list[Change] = []

    def truth(self) -> Grid:
        truth = self.static.copy()
        for footprint, row, col in self.movables.values():
            h, w = footprint.shape
            truth[row : row + h, col : col + w] |= footprint
        return truth

    def kind(self, row: int, col: int) -> int:
        """Model kind of a cell: 1 static wall (or off-map), 2 movable only, 0 free."""
        rows, cols = self.static.shape
        if not (0 <= row < rows and 0 <= col < cols) or self.static[row, col]:
            return 1
        return 2 if self.truth()[row, col] else 0

    def apply(self, mutate: object) -> None:
        """Run a mutation and check the Change it returns against the model."""
        before, version = self.world.occupied.copy(), self.world.version
        change = mutate()  # type: ignore[operator]
        after = self.truth()
        flipped = before != after
        assert isinstance(change, Change)
        assert self.world.version == version + bool(flipped.any()) == change.version
        assert bool(change) == bool(flipped.any())
        reported = np.zeros_like(flipped)
        for patch in change.patches:
            r0, r1, c0, c1 = patch.box
            assert not reported[r0:r1, c0:c1][patch.flipped].any()
            reported[r0:r1, c0:c1] |= patch.flipped
            np.testing.assert_array_equal(patch.occupied, after[r0:r1, c0:c1])
        np.testing.assert_array_equal(reported, flipped)
        closed = np.argwhere(flipped & after)
        expected = any(circle_overlaps_cell(*self.robot, ROBOT_RADIUS, r, c) for r, c in closed)
        assert change.robots == ((0,) if expected else ())
        self.pending.append(change)

    @rule(data=st.data())
    def set_cells(self, data: st.DataObject) -> None:
        rows, cols = self.static.shape
        row0 = data.draw(st.integers(0, rows - 1))
        row1 = data.draw(st.integers(row0 + 1, min(rows, row0 + 4)))
        col0 = data.draw(st.integers(0, cols - 1))
        col1 = data.draw(st.integers(col0 + 1, min(cols, col0 + 4)))
        value = data.draw(
            st.booleans() | arrays(np.bool_, (row1 - row0, col1 - col0), elements=st.booleans())
        )
        self.static[row0:row1, col0:col1] = value
        self.apply(lambda: self.world.set_cells((row0, row1, col0, col1), value))

    def place(self, data: st.DataObject, footprint: Grid) -> tuple[int, int]:
        rows, cols = self.static.shape
        h, w = footprint.shape
        return data.draw(st.integers(0, rows - h)), data.draw(st.integers(0, cols - w))

    @rule(name=st.sampled_from(["cart", "door"]), footprint=footprints, data=st.data())
    def add_movable(self, name: str, footprint: Grid, data: st.DataObject) -> None:
        if name in self.movables or not footprint.any():
            return
        row, col = self.place(data, footprint)
        self.movables[name] = (footprint, row, col)
        self.apply(lambda: self.world.add_movable(name, footprint, (row, col)))

    @precondition(lambda self: bool(self.movables))
    @rule(data=st.data(), reshape=footprints)
    def move_movable(self, data: st.DataObject, reshape: Grid) -> None:
        name = data.draw(st.sampled_from(sorted(self.movables)))
        footprint = reshape if reshape.any() else self.movables[name][0]
        row, col = self.place(data, footprint)
        self.movables[name] = (footprint, row, col)
        new = reshape if reshape.any() else None
        self.apply(lambda: self.world.move_movable(name, (row, col), new))

    @precondition(lambda self: bool(self.movables))
    @rule(data=st.data())
    def remove_movable(self, data: st.DataObject) -> None:
        name = data.draw(st.sampled_from(sorted(self.movables)))
        del self.movables[name]
        self.apply(lambda: self.world.remove_movable(name))

    @rule()
    def follow_reachable(self) -> None:
        self.reachable.follow(self.world.occupied, self.pending)
        self.pending = []
        free = ~self.world.occupied
        labels, _ = ndimage.label(free)  # 4-connected by default
        expected = labels == labels[0, 0] if free[0, 0] else np.zeros_like(free)
        np.testing.assert_array_equal(self.reachable.mask, expected)

    @rule(seed=st.integers(0, 2**32 - 1))
    def rays_match_the_grid(self, seed: int) -> None:
        grid = self.world.occupied
        free = np.argwhere(~grid)
        if len(free) == 0:
            return
        rng = np.random.default_rng(seed)
        walls = self.world.query_filter(None, robots_block=False)
        for row, col in free[rng.integers(0, len(free), 8)]:
            origin = (col + rng.uniform(0.01, 0.99), row + rng.uniform(0.01, 0.99))
            angles = rng.uniform(-np.pi, np.pi, 12)
            scan = self.world.cast_rays(origin, angles, 100.0, walls)
            for angle, distance, hit in zip(angles, scan.ranges, scan.wall_hit, strict=True):
                truth, near_vertex = dda_first_hit(grid, *origin, math.cos(angle), math.sin(angle))
                if not near_vertex:
                    assert hit and abs(distance - truth) < RAY_TOL, (origin, angle, distance, truth)
                    # the Space's segments (a Chipmunk query) stop the ray there too
                    end = (origin[0] + 100 * math.cos(angle), origin[1] + 100 * math.sin(angle))
                    found = self.world.first_hit(origin, end, 0.0, walls)
                    assert found is not None and abs(found.alpha * 100 - truth) < RAY_TOL

    @invariant()
    def truth_is_the_model(self) -> None:
        np.testing.assert_array_equal(self.world.occupied, self.truth())

    @invariant()
    def space_holds_the_static_walls_and_each_movables_outline(self) -> None:
        held = space_segments(self.world)
        static = [(segment, cat) for segment, cat, on_static in held if on_static]
        walls = sorted(map(tuple, wall_segments(self.static).tolist()))
        assert sorted(s for s, _ in static) == walls
        assert {cat for _, cat in static} <= {WALL_CATEGORY}
        assert len(self.world.segments) == len(static)
        outlines = [(e, c) for s, c, on_static in held if not on_static for e in unit_edges([s])]
        expected = []
        for footprint, row, col in self.movables.values():
            h, w = footprint.shape  # the outline: boundary edges of the padded footprint
            for x0, y0, x1, y1 in unit_edges(wall_segments(np.pad(footprint, 1))):
                inside = min(x0, x1) > 0 and max(x0, x1) < w + 2
                if inside and min(y0, y1) > 0 and max(y0, y1) < h + 2:
                    expected.append((x0 + col - 1, y0 + row - 1, x1 + col - 1, y1 + row - 1))
        assert sorted(e for e, _ in outlines) == sorted(expected)
        assert {cat for _, cat in outlines} <= {MOVABLE_CATEGORY}
        # together: every boundary edge of the truth, and only edges with an occupied side
        edges = {e for s, _, _ in held for e in unit_edges([s])}
        assert set(unit_edges(wall_segments(self.world.occupied))) <= edges
        rows, cols = self.static.shape
        for edge in edges:
            row, col = occupied_side(edge)
            inside = 0 <= row < rows and 0 <= col < cols
            assert not inside or self.world.occupied[row, col], edge


ChangingWorld.TestCase.settings = settings(max_examples=60, stateful_step_count=25, deadline=None)
test_changing_world = ChangingWorld.TestCase
