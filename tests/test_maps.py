"""Tests for phase 1 geometry kernels: exact wall segments and reachable free space."""

from __future__ import annotations

import math
from pathlib import Path
from types import ModuleType

import numpy as np
import pymunk
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from numpy.typing import NDArray
from scipy import ndimage
from tool_modules import load_tool

from mresim_phys.errors import MapError
from mresim_phys.scenario.readers import load_map
from mresim_phys.world.maps import (
    connected_to,
    edge_segments,
    free_components_mask,
    padded_kinds,
    wall_segments,
)

Grid = NDArray[np.bool_]
VERTEX_TOL = 1e-9

small_grids = arrays(
    np.bool_, st.tuples(st.integers(1, 9), st.integers(1, 9)), elements=st.booleans()
)


def grid_of(text: str) -> Grid:
    """Parse a picture of a grid: ``#`` = occupied, ``.`` = free, one line per row."""
    rows = [line.strip() for line in text.strip().splitlines()]
    return np.array([[ch == "#" for ch in row] for row in rows], dtype=bool)


def is_occupied(grid: Grid, x: float, y: float) -> bool:
    """Occupancy of the cell containing (x, y); outside the grid counts as occupied."""
    row, col = math.floor(y), math.floor(x)
    inside = 0 <= row < grid.shape[0] and 0 <= col < grid.shape[1]
    return not inside or bool(grid[row, col])


def boundary_edges(grid: Grid) -> set[tuple[float, float, float, float]]:
    """Brute force: every occupied/free unit edge as (x0, y0, x1, y1), lowest end first."""
    edges = set()
    rows, cols = grid.shape
    for y in range(rows + 1):
        for x in range(cols):
            if is_occupied(grid, x + 0.5, y - 0.5) != is_occupied(grid, x + 0.5, y + 0.5):
                edges.add((x, y, x + 1, y))
    for x in range(cols + 1):
        for y in range(rows):
            if is_occupied(grid, x - 0.5, y + 0.5) != is_occupied(grid, x + 0.5, y + 0.5):
                edges.add((x, y, x, y + 1))
    return edges


def unit_pieces(seg: NDArray[np.float64]) -> list[tuple[float, ...]]:
    """Split one axis-aligned integer segment into its unit edges (direction kept)."""
    x0, y0, x1, y1 = seg
    n = round(abs(x1 - x0) + abs(y1 - y0))
    dx, dy = (x1 - x0) / n, (y1 - y0) / n
    return [(x0 + k * dx, y0 + k * dy, x0 + (k + 1) * dx, y0 + (k + 1) * dy) for k in range(n)]


def dda_first_hit(grid: Grid, x: float, y: float, dx: float, dy: float) -> tuple[float, bool]:
    """Amanatides-Woo traversal: distance to the first occupied cell, and a near-vertex flag."""
    col, row = math.floor(x), math.floor(y)
    step_x, step_y = (1 if dx > 0 else -1), (1 if dy > 0 else -1)
    t_x = ((col + (dx > 0) - x) / dx) if dx else math.inf
    t_y = ((row + (dy > 0) - y) / dy) if dy else math.inf
    delta_x = abs(1 / dx) if dx else math.inf
    delta_y = abs(1 / dy) if dy else math.inf
    near_vertex = False
    while True:
        near_vertex |= abs(t_x - t_y) < VERTEX_TOL
        if t_x < t_y:
            col, t, t_x = col + step_x, t_x, t_x + delta_x
        else:
            row, t, t_y = row + step_y, t_y, t_y + delta_y
        if is_occupied(grid, col + 0.5, row + 0.5):
            return t, near_vertex


def build_space(segments: NDArray[np.float64]) -> pymunk.Space:
    space = pymunk.Space()
    body = space.static_body
    space.add(*[pymunk.Segment(body, (s[0], s[1]), (s[2], s[3]), 0) for s in segments])
    return space


def pymunk_first_hit(space: pymunk.Space, x: float, y: float, dx: float, dy: float) -> float:
    length = 1000.0
    hit = space.segment_query_first(
        (x, y), (x + dx * length, y + dy * length), 0, pymunk.ShapeFilter()
    )
    assert hit is not None, f"ray from ({x}, {y}) dir ({dx}, {dy}) escaped"
    return hit.alpha * length


def random_grid(rng: np.random.Generator) -> Grid:
    rows, cols = rng.integers(1, 14, size=2)
    kind = rng.integers(0, 4)
    if kind == 0:
        return rng.random((rows, cols)) < rng.uniform(0.05, 0.6)
    if kind == 1:  # checkerboard patches: many corner-touching cells
        board = (np.add.outer(np.arange(rows), np.arange(cols)) % 2).astype(bool)
        return board & (rng.random((rows, cols)) < 0.8)
    if kind == 2:  # diagonal lines of single cells
        eye = np.eye(rows, cols, k=int(rng.integers(-2, 3)), dtype=bool)
        return eye | (np.fliplr(np.eye(rows, cols, dtype=bool)) & (rng.random() < 0.5))
    grid = np.zeros((rows, cols), dtype=bool)  # single-cell walls touching the border
    grid[rng.integers(0, rows, 4), rng.integers(0, cols, 4)] = True
    return grid


def ray_cases(grid: Grid, rng: np.random.Generator, n: int) -> list[tuple[float, ...]]:
    """Random rays from random points of free cells, plus axis rays from free cell centres."""
    free = np.argwhere(~grid)
    picks = free[rng.integers(0, len(free), n)]
    points = picks[:, ::-1] + rng.uniform(0.001, 0.999, size=(n, 2))
    angles = rng.uniform(0, 2 * np.pi, n)
    cases = [(px, py, math.cos(a), math.sin(a)) for (px, py), a in zip(points, angles, strict=True)]
    row, col = picks[0]
    cases += [(col + 0.5, row + 0.5, dx, dy) for dx, dy in ((1, 0), (-1, 0), (0, 1), (0, -1))]
    return cases


def test_rays_stop_exactly_where_the_grid_dda_stops() -> None:
    rng = np.random.default_rng(20240601)
    checked = skipped = 0
    for _ in range(80):
        grid = random_grid(rng)
        if grid.all():
            continue
        space = build_space(wall_segments(grid))
        for x, y, dx, dy in ray_cases(grid, rng, 60):
            truth, near_vertex = dda_first_hit(grid, x, y, dx, dy)
            if near_vertex:
                skipped += 1
                continue
            assert pymunk_first_hit(space, x, y, dx, dy) == pytest.approx(truth, abs=1e-6), (
                f"grid\n{grid.astype(int)}\nray ({x}, {y}) dir ({dx}, {dy})"
            )
            checked += 1
    assert checked > 4000
    assert skipped < checked / 100


def test_diagonal_gap_between_corner_touching_cells_is_closed() -> None:
    grid = grid_of("""
        #.
        .#
    """)
    space = build_space(wall_segments(grid))
    # From the free cell (col 1, row 0) straight through the shared vertex (1, 1).
    d = math.sqrt(0.5)
    assert pymunk_first_hit(space, 1.5, 0.5, -d, d) == pytest.approx(math.sqrt(0.5))


@settings(max_examples=150, deadline=None)
@given(small_grids)
def test_segments_cover_each_boundary_edge_once_with_occupied_side_on_the_normal(
    grid: Grid,
) -> None:
    segments = wall_segments(grid)
    pieces = [piece for seg in segments for piece in unit_pieces(seg)]
    normalised = [tuple(min((a, b), (c, d))) + tuple(max((a, b), (c, d))) for a, b, c, d in pieces]
    assert len(normalised) == len(set(normalised))
    assert set(normalised) == boundary_edges(grid)
    for x0, y0, x1, y1 in pieces:
        mx, my = (x0 + x1) / 2, (y0 + y1) / 2
        nx, ny = -(y1 - y0), x1 - x0
        assert is_occupied(grid, mx + 0.25 * nx, my + 0.25 * ny)
        assert not is_occupied(grid, mx - 0.25 * nx, my - 0.25 * ny)


@settings(max_examples=150, deadline=None)
@given(small_grids)
def test_total_length_equals_number_of_boundary_unit_edges(grid: Grid) -> None:
    padded = np.pad(grid, 1, constant_values=True)
    n_edges = np.count_nonzero(padded[1:] != padded[:-1])
    n_edges += np.count_nonzero(padded[:, 1:] != padded[:, :-1])
    segments = wall_segments(grid)
    lengths = np.abs(segments[:, 2] - segments[:, 0]) + np.abs(segments[:, 3] - segments[:, 1])
    assert lengths.sum() == n_edges
    assert ((segments[:, 0] == segments[:, 2]) | (segments[:, 1] == segments[:, 3])).all()


@settings(max_examples=150, deadline=None)
@given(small_grids)
def test_collinear_runs_are_merged_maximally(grid: Grid) -> None:
    segments = wall_segments(grid)
    direction = np.sign(segments[:, 2:] - segments[:, :2]).tolist()
    starts = {(*start, *d) for start, d in zip(segments[:, :2].tolist(), direction, strict=True)}
    for end, d in zip(segments[:, 2:].tolist(), direction, strict=True):
        assert (*end, *d) not in starts, "a collinear continuation was not merged"


@settings(max_examples=150, deadline=None)
@given(small_grids)
def test_edge_segments_of_the_whole_grid_are_wall_segments(grid: Grid) -> None:
    kinds = padded_kinds(grid)
    rows, cols = grid.shape
    horizontal, h_kinds = edge_segments(kinds, 0, (0, rows), (0, cols))
    vertical, v_kinds = edge_segments(kinds, 1, (0, cols), (0, rows))
    np.testing.assert_array_equal(np.concatenate((horizontal, vertical)), wall_segments(grid))
    assert (np.concatenate((h_kinds, v_kinds)) == 1).all()


def test_edge_segments_break_runs_where_the_occupied_kind_changes() -> None:
    kinds = padded_kinds(grid_of("......\n......"))
    kinds[2, 2:6] = [1, 1, 2, 2]  # row 1: two wall cells, then two movable cells
    segments, kind = edge_segments(kinds, 0, (1, 1), (0, 6))  # the line y = 1 above them
    assert segments.tolist() == [[1.0, 1.0, 3.0, 1.0], [3.0, 1.0, 5.0, 1.0]]
    assert kind.tolist() == [1, 2]
    segments, kind = edge_segments(kinds, 0, (1, 1), (2, 4))  # a window cuts the run
    assert segments.tolist() == [[2.0, 1.0, 3.0, 1.0], [3.0, 1.0, 4.0, 1.0]]


def test_connected_to_ignores_seeds_on_occupied_cells() -> None:
    free = ~grid_of("..#..")
    cells = np.array([[0, 2], [0, 4]])
    assert connected_to(free, cells).tolist() == [[False, False, False, True, True]]
    assert not connected_to(free, cells[:1]).any()


@pytest.mark.parametrize(
    ("picture", "expected"),
    [
        ("....\n....\n....", 4),  # empty room: just the border
        ("###\n#.#\n###", 4),  # one free cell
        ("#.\n.#", 8),  # corner-touching cells: segments meet at the vertex
        ("..............\n..##########..\n..............", 8),  # 10x1 wall: 4 + border 4
        ("..#..\n.....\n.....\n.....\n.....", 8),  # wall cell on the border: border splits
        ("......\n.####.\n.####.\n......", 8),  # thick wall: its own 4 faces
    ],
)
def test_segment_counts_on_hand_built_grids(picture: str, expected: int) -> None:
    assert len(wall_segments(grid_of(picture))) == expected


def test_all_occupied_grid_has_no_segments_and_output_is_deterministic() -> None:
    assert wall_segments(np.ones((3, 4), dtype=bool)).shape == (0, 4)
    grid = np.random.default_rng(3).random((40, 50)) < 0.3
    first, second = wall_segments(grid), wall_segments(grid.copy())
    assert first.dtype == np.float64
    np.testing.assert_array_equal(first, second)


def test_empty_grid_is_rejected() -> None:
    with pytest.raises(ValueError, match="non-empty"):
        wall_segments(np.zeros((0, 5), dtype=bool))


def test_free_components_mask_keeps_only_regions_reachable_from_seeds() -> None:
    grid = grid_of("""
        ..#..
        ..#..
        #####
        ...#.
    """)
    left = free_components_mask(grid, (0.5, 0.5))
    assert left.sum() == 4 and left[:2, :2].all()
    both = free_components_mask(grid, [(0.5, 0.5), (4.2, 3.9)])
    assert both.sum() == 5 and both[3, 4] and not both[0, 3]


def test_free_components_mask_treats_corner_contact_as_closed() -> None:
    grid = grid_of("""
        .#
        #.
    """)
    assert free_components_mask(grid, (0.5, 0.5)).tolist() == [[True, False], [False, False]]


@pytest.mark.parametrize(("seed", "message"), [((1.5, 0.5), "obstacle"), ((2.5, 0.5), "outside")])
def test_free_components_mask_rejects_bad_seeds(seed: tuple[float, float], message: str) -> None:
    with pytest.raises(MapError, match=message):
        free_components_mask(grid_of(".#"), seed)


# --- shipped maps -----------------------------------------------------------------------

REPO = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def make_maps() -> ModuleType:
    """The map generator script, imported from ``tools/make_maps.py``."""
    return load_tool("make_maps")


def generated_truth(make_maps: ModuleType, name: str) -> Grid:
    picture = make_maps.BUILDERS[name]()
    if name == "cave":
        return picture
    return picture != (make_maps.ROS_FREE if name == "warehouse" else make_maps.FREE)


SHIPPED = ["office", "small_rooms", "cave", "warehouse", "maze", "rubble"]


def test_every_generated_map_is_tested(make_maps: ModuleType) -> None:
    assert list(make_maps.MAPS) == SHIPPED and list(make_maps.BUILDERS) == SHIPPED


@pytest.mark.parametrize("name", SHIPPED)
def test_shipped_maps_are_up_to_date_and_their_starts_are_usable(
    make_maps: ModuleType, name: str
) -> None:
    loaded = load_map(REPO / "maps" / make_maps.MAPS[name].file)
    np.testing.assert_array_equal(loaded.occupied, generated_truth(make_maps, name))
    stats = make_maps.check(name, loaded)  # raises if a start is blocked or cut off
    assert stats.reachable == stats.free


def test_shipped_map_metadata() -> None:
    office = load_map(REPO / "maps" / "office.png").occupied
    assert office.shape == (600, 800) and 0.55 < 1 - office.mean() < 0.75
    assert load_map(REPO / "maps" / "small_rooms.png").occupied.shape == (120, 160)
    warehouse = load_map(REPO / "maps" / "warehouse.yaml")
    assert warehouse.resolution == 0.05 and warehouse.origin == (-7.5, -5.0, 0.0)
    maze = load_map(REPO / "maps" / "maze.png").occupied
    assert maze.shape == (450, 600) and 0.8 < 1 - maze.mean() < 0.95
    rubble = load_map(REPO / "maps" / "rubble.png").occupied
    assert rubble.shape == (400, 500) and 0.85 < 1 - rubble.mean() < 0.97


def free_runs(line: NDArray[np.bool_]) -> list[tuple[int, int]]:
    """(start, length) of each run of False in a 1-D occupancy line."""
    edges = np.diff(np.concatenate(([1], line.astype(np.int8), [1])))
    starts, ends = np.flatnonzero(edges == -1), np.flatnonzero(edges == 1)
    return [(int(a), int(b - a)) for a, b in zip(starts, ends, strict=True)]


def test_maze_openings_let_a_radius_2_robot_with_a_margin_through(make_maps: ModuleType) -> None:
    occupied = load_map(REPO / "maps" / "maze.png").occupied
    pitch = make_maps.MAZE_PITCH
    fits = make_maps.clearance(occupied) >= 3.0  # centre of a radius-2 robot, 1 cell to spare
    widths = []
    for grid, room in ((occupied, fits), (occupied.T, fits.T)):  # vertical, then horizontal walls
        for at in range(pitch, grid.shape[1], pitch):  # a wall covers [at - 1, at + 1)
            assert grid[:, at - 1].sum() == grid[:, at].sum()  # doors cut the whole thickness
            for start, length in free_runs(grid[:, at]):
                widths.append(length)
                assert room[start + length // 2, at], f"robot does not fit at {at}, {start}"
    lobby = [w for w in widths if w >= pitch]
    assert len(lobby) == 2  # the lobby's two open walls
    assert all(10 <= w <= 14 for w in widths if w < pitch)
    rooms_x, rooms_y = occupied.shape[1] // pitch, occupied.shape[0] // pitch
    doors = len(widths) + 2  # the lobby's 2 runs open 4 walls
    assert doors > 1.1 * (rooms_x * rooms_y - 1)  # loops: well over a spanning tree's doors
    labels, _ = ndimage.label(fits)
    x, y = make_maps.MAPS["maze"].base
    centres = np.arange(rooms_x) * pitch + pitch // 2, np.arange(rooms_y) * pitch + pitch // 2
    assert (labels[np.ix_(centres[1], centres[0])] == labels[y, x]).all()


def test_rubble_is_scattered_and_open_to_a_robot(make_maps: ModuleType) -> None:
    occupied = load_map(REPO / "maps" / "rubble.png").occupied
    inner = occupied.copy()
    inner[:3], inner[-3:], inner[:, :3], inner[:, -3:] = False, False, False, False
    _, pieces = ndimage.label(inner, structure=np.ones((3, 3)))
    assert 90 <= pieces <= 140  # ~120 pieces (some overlap) and the wall remnants
    fits = make_maps.clearance(occupied) >= 3.0
    labels, _ = ndimage.label(fits)
    x, y = make_maps.MAPS["rubble"].base
    assert (labels == labels[y, x]).sum() > 0.99 * fits.sum()


def test_rays_on_the_office_map_match_the_dda() -> None:
    grid = load_map(REPO / "maps" / "office.png").occupied
    segments = wall_segments(grid)
    assert 500 < len(segments) < 5000
    space = build_space(segments)
    rng = np.random.default_rng(11)
    for x, y, dx, dy in ray_cases(grid, rng, 300):
        truth, near_vertex = dda_first_hit(grid, x, y, dx, dy)
        if not near_vertex:
            assert pymunk_first_hit(space, x, y, dx, dy) == pytest.approx(truth, abs=1e-6)
