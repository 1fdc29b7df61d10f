"""Phase 4b: configuration space, Dijkstra distance fields and paths on a belief grid."""

from __future__ import annotations

import heapq
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mresim_phys.planning.fields import (
    distance_field,
    path_length,
    plan_path,
    snap_to_passable,
    traversable,
)
from mresim_phys.planning.grid import DIAGONAL, MOVES, STRAIGHT, diagonal_ok
from mresim_phys.types import FREE, OCCUPIED, UNKNOWN

SEEDS = st.integers(0, 2**32 - 1)


def reference_dijkstra(passable: np.ndarray, start: tuple[int, int]) -> np.ndarray:
    """Plain heapq Dijkstra with the module's move rules (octile, no squeezing diagonals)."""
    rows, cols = passable.shape
    dist = np.full(passable.shape, np.inf)
    dist[start] = 0.0
    heap = [(0.0, start)]
    while heap:
        d, (r, c) = heapq.heappop(heap)
        if d > dist[r, c]:
            continue
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                nr, nc = r + dr, c + dc
                if (dr, dc) == (0, 0) or not (0 <= nr < rows and 0 <= nc < cols):
                    continue
                if not passable[nr, nc]:
                    continue
                if dr and dc and not (passable[nr, c] or passable[r, nc]):
                    continue
                nd = d + (math.sqrt(2.0) if dr and dc else 1.0)
                if nd < dist[nr, nc]:
                    dist[nr, nc] = nd
                    heapq.heappush(heap, (nd, (nr, nc)))
    return dist


def random_passable(seed: int, shape: tuple[int, int] = (12, 12)) -> np.ndarray:
    rng = np.random.default_rng(seed)
    density = rng.uniform(0.05, 0.55)
    return rng.random(shape) > density


def random_start(passable: np.ndarray, seed: int) -> tuple[int, int] | None:
    rr, cc = np.nonzero(passable)
    if len(rr) == 0:
        return None
    i = np.random.default_rng(seed + 1).integers(len(rr))
    return int(rr[i]), int(cc[i])


def assert_valid_path(path: np.ndarray, passable: np.ndarray) -> None:
    """Cell centres, passable cells, 8-neighbour steps, no squeezing diagonal."""
    cells = np.floor(path[:, ::-1]).astype(int)
    np.testing.assert_allclose(path, cells[:, ::-1] + 0.5)
    assert passable[cells[:, 0], cells[:, 1]].all()
    steps = np.diff(cells, axis=0)
    assert (np.abs(steps).max(axis=1) == 1).all()
    diag = np.flatnonzero(np.abs(steps).sum(axis=1) == 2)
    a, s = cells[diag], steps[diag]
    assert (passable[a[:, 0] + s[:, 0], a[:, 1]] | passable[a[:, 0], a[:, 1] + s[:, 1]]).all()


# --------------------------------------------------------------------------- move rule


def test_move_rule_is_the_documented_one() -> None:
    """grid's MOVES, costs and corner rule: the one move rule of every grid search."""
    raster = tuple((dr, dc) for dr in (-1, 0, 1) for dc in (-1, 0, 1) if (dr, dc) != (0, 0))
    assert raster == MOVES  # raster order: neighbours are visited in it, which settles ties
    assert STRAIGHT == 1.0
    assert math.sqrt(2.0) == DIAGONAL
    for bits in range(16):  # the four straight neighbours of the centre of a 3x3 mask
        pad = np.zeros((3, 3), dtype=np.bool_)
        pad[0, 1], pad[2, 1], pad[1, 0], pad[1, 2] = ((bits >> k) & 1 == 1 for k in range(4))
        for dr, dc in ((dr, dc) for dr, dc in MOVES if dr and dc):
            allowed = diagonal_ok(pad.ravel(), 3, 4, dr, dc)
            assert allowed == bool(pad[1 + dr, 1] or pad[1, 1 + dc])


# --------------------------------------------------------------------------- distance field


@settings(max_examples=150, deadline=None)
@given(seed=SEEDS)
def test_costs_equal_reference_dijkstra(seed: int) -> None:
    passable = random_passable(seed)
    start = random_start(passable, seed)
    if start is None:
        return
    field = distance_field(passable, (start[1] + 0.3, start[0] + 0.8))
    expected = reference_dijkstra(passable, start)
    assert field.start_rc == start
    assert field.costs.shape == passable.shape
    np.testing.assert_array_equal(np.isinf(field.costs), np.isinf(expected))
    finite = np.isfinite(expected)
    np.testing.assert_allclose(field.costs[finite], expected[finite], rtol=0, atol=1e-9)


@settings(max_examples=80, deadline=None)
@given(seed=SEEDS)
def test_paths_are_valid_and_cost_what_the_field_says(seed: int) -> None:
    passable = random_passable(seed, (14, 11))
    start = random_start(passable, seed)
    if start is None:
        return
    field = distance_field(passable, (start[1] + 0.5, start[0] + 0.5))
    for row, col in zip(*np.nonzero(passable), strict=True):
        path = field.path_to(int(row), int(col))
        if not field.reachable(int(row), int(col)):
            assert path.shape == (0, 2)
            continue
        assert_valid_path(path, passable)
        np.testing.assert_allclose(path[0], (start[1] + 0.5, start[0] + 0.5))
        np.testing.assert_allclose(path[-1], (col + 0.5, row + 0.5))
        cost = field.cost_at(np.array([row]), np.array([col]))[0]
        assert path_length(path) == pytest.approx(cost, abs=1e-9)


@settings(max_examples=60, deadline=None)
@given(seed=SEEDS, limit=st.floats(0.0, 30.0))
def test_limit_keeps_exact_costs_up_to_the_limit_and_drops_the_rest(
    seed: int, limit: float
) -> None:
    passable = random_passable(seed, (25, 30))
    start = random_start(passable, seed)
    if start is None:
        return
    field = distance_field(passable, (start[1] + 0.5, start[0] + 0.5), limit=limit)
    expected = reference_dijkstra(passable, start)
    expected[expected > limit] = np.inf
    np.testing.assert_array_equal(np.isinf(field.costs), np.isinf(expected))
    finite = np.isfinite(expected)
    np.testing.assert_allclose(field.costs[finite], expected[finite], atol=1e-9)
    row, col = np.argwhere(finite)[-1]
    assert path_length(field.path_to(row, col)) == pytest.approx(expected[row, col], abs=1e-9)


def test_search_restricted_to_a_corner_of_a_big_grid_matches_reference() -> None:
    passable = np.zeros((60, 70), dtype=bool)
    passable[40:52, 50:62] = random_passable(7)
    start = (46, 55)
    passable[start] = True
    field = distance_field(passable, (55.5, 46.5))
    expected = reference_dijkstra(passable, start)
    np.testing.assert_array_equal(np.isinf(field.costs), np.isinf(expected))
    finite = np.isfinite(expected)
    np.testing.assert_allclose(field.costs[finite], expected[finite], atol=1e-9)
    rows, cols = np.nonzero(finite)
    np.testing.assert_allclose(field.cost_at(rows, cols), expected[finite], atol=1e-9)


def test_unreachable_goal_gives_inf_and_empty_path() -> None:
    passable = np.ones((10, 10), dtype=bool)
    passable[:, 5] = False
    field = distance_field(passable, (1.5, 1.5))
    assert field.cost_at(np.array([3]), np.array([8]))[0] == np.inf
    assert not field.reachable(3, 8)
    assert not field.reachable(3, 5)
    assert field.path_to(3, 8).shape == (0, 2)
    assert field.cost_at(np.array([-1, 3]), np.array([0, 99])).tolist() == [np.inf, np.inf]
    assert plan_path(passable, (1.5, 1.5), (8.5, 3.5)).shape == (0, 2)
    assert plan_path(passable, (1.5, 1.5), (5.5, 3.5)).shape == (0, 2)  # goal blocked


def test_no_squeezing_between_two_blocked_orthogonal_cells() -> None:
    passable = np.array([[1, 0], [0, 1]], dtype=bool)
    assert not distance_field(passable, (0.5, 0.5)).reachable(1, 1)
    passable[0, 1] = True  # one orthogonal free: the diagonal is allowed
    field = distance_field(passable, (0.5, 0.5))
    assert field.cost_at(np.array([1]), np.array([1]))[0] == pytest.approx(math.sqrt(2.0))
    np.testing.assert_allclose(field.path_to(1, 1), [[0.5, 0.5], [1.5, 1.5]])


def test_l_shaped_corridor_path_goes_around_the_wall() -> None:
    passable = np.zeros((20, 20), dtype=bool)
    passable[2:5, 2:17] = True  # horizontal leg
    passable[2:18, 14:17] = True  # vertical leg
    field = distance_field(passable, (3.5, 3.5))
    path = field.path_to(16, 3 + 12)
    assert_valid_path(path, passable)
    assert np.hypot(path[:, 0] - 14.0, path[:, 1] - 5.0).min() < 1.0  # hugs the inner corner
    assert path_length(path) == pytest.approx(field.cost_at(np.array([16]), np.array([15]))[0])
    assert path_length(path) == pytest.approx(reference_dijkstra(passable, (3, 3))[16, 15])
    assert path_length(path) > math.hypot(15 - 3, 16 - 3) + 1.0  # not a straight line


# --------------------------------------------------------------------------- snapping


def test_start_snaps_to_nearest_passable_cell() -> None:
    passable = np.zeros((10, 10), dtype=bool)
    passable[5:, :] = True
    field = distance_field(passable, (3.2, 3.9))  # cell (3, 3) blocked; (5, 3) is 1.6 away
    assert field.start_rc == (5, 3)
    path = field.path_to(7, 3)
    np.testing.assert_allclose(path, [[3.5, 5.5], [3.5, 6.5], [3.5, 7.5]])
    assert field.cost_at(np.array([5]), np.array([3]))[0] == 0.0


def test_snap_ties_are_deterministic_and_limited_by_max_snap() -> None:
    passable = np.zeros((9, 9), dtype=bool)
    passable[4, 2] = passable[4, 6] = passable[2, 4] = passable[6, 4] = True
    assert snap_to_passable(passable, (4.5, 4.5), 2.0) == (2, 4)  # four at 2.0: smallest rc
    assert snap_to_passable(passable, (4.5, 4.5), 1.9) is None
    field = distance_field(passable, (4.5, 4.5), max_snap=1.5)
    assert field.start_rc is None
    assert np.isinf(field.costs).all()
    assert field.path_to(4, 2).shape == (0, 2)
    assert snap_to_passable(passable, (-0.5, 4.5), 3.0) == (4, 2)  # start off the grid


# --------------------------------------------------------------------------- plan_path


@settings(max_examples=40, deadline=None)
@given(seed=SEEDS)
def test_plan_path_cost_equals_field_cost(seed: int) -> None:
    passable = random_passable(seed, (50, 60))
    start = random_start(passable, seed)
    goal = random_start(passable, seed + 7)
    if start is None or goal is None:
        return
    start_xy, goal_xy = (start[1] + 0.5, start[0] + 0.5), (goal[1] + 0.2, goal[0] + 0.9)
    expected = distance_field(passable, start_xy).cost_at(np.array([goal[0]]), np.array([goal[1]]))
    path = plan_path(passable, start_xy, goal_xy)
    if np.isinf(expected[0]):
        assert path.shape == (0, 2)
        return
    assert_valid_path(path, passable)
    assert path_length(path) == pytest.approx(expected[0], abs=1e-9)


def test_plan_path_in_a_long_serpentine_needs_several_rounds() -> None:
    passable = np.ones((41, 41), dtype=bool)
    for k, row in enumerate(range(3, 40, 4)):  # full-width walls, gaps alternating sides
        passable[row, :] = False
        passable[row, 40 if k % 2 == 0 else 0] = True
    path = plan_path(passable, (1.5, 0.5), (1.5, 40.5))
    expected = reference_dijkstra(passable, (0, 1))[40, 1]
    assert np.isfinite(expected)
    assert_valid_path(path, passable)
    assert path_length(path) == pytest.approx(expected, abs=1e-9)


# --------------------------------------------------------------------------- C-space


def box_distance_to_occupied(belief: np.ndarray) -> np.ndarray:
    """Brute force: distance from every cell centre to the nearest occupied square.

    Cells outside the grid count as occupied: the distance to them is the distance to the
    grid edge.
    """
    rows, cols = belief.shape
    r, c = np.mgrid[0:rows, 0:cols]
    best = np.minimum.reduce([r + 0.5, rows - r - 0.5, c + 0.5, cols - c - 0.5])
    for orow, ocol in zip(*np.nonzero(belief == OCCUPIED), strict=True):
        gr = np.maximum(np.abs(r - orow) - 0.5, 0.0)
        gc = np.maximum(np.abs(c - ocol) - 0.5, 0.0)
        best = np.minimum(best, np.sqrt(gr**2 + gc**2))
    return best


@settings(max_examples=100, deadline=None)
@given(seed=SEEDS, clearance=st.sampled_from([0.0, 0.5, 0.8, 1.0, 1.25, 1.5, 2.2, 2.5, 3.7]))
def test_traversable_is_free_and_clear_of_known_obstacles(seed: int, clearance: float) -> None:
    rng = np.random.default_rng(seed)
    shape = tuple(rng.integers(5, 25, size=2))
    belief = rng.choice(np.array([UNKNOWN, FREE, OCCUPIED]), size=shape, p=rng.dirichlet([1, 4, 1]))
    passable = traversable(belief, clearance)
    dist = box_distance_to_occupied(belief)
    assert passable.shape == belief.shape
    assert not passable[belief != FREE].any()
    assert not passable[dist < clearance - 1e-12].any()
    np.testing.assert_array_equal(passable, (belief == FREE) & (dist >= clearance - 1e-12))


def test_unknown_cells_are_not_inflated() -> None:
    belief = np.full((9, 9), FREE, dtype=np.uint8)
    belief[:, 5:] = UNKNOWN
    passable = traversable(belief, 2.0)
    assert passable[4, 4]  # next to unknown, 4.5 from the grid edge
    assert passable[2:7, 2:5].all()
    assert not passable[:, 5:].any()
    assert not passable[:2].any() and not passable[:, :2].any()  # grid edge counts as wall


def test_traversable_of_an_unexplored_map_is_empty() -> None:
    belief = np.zeros((30, 40), dtype=np.uint8)
    assert not traversable(belief, 1.5).any()
    assert distance_field(traversable(belief, 1.5), (3.0, 3.0)).start_rc is None


def test_path_length() -> None:
    assert path_length(np.empty((0, 2))) == 0.0
    assert path_length(np.array([[1.0, 1.0]])) == 0.0
    assert path_length(np.array([[0.0, 0.0], [3.0, 4.0], [3.0, 5.0]])) == pytest.approx(6.0)


def test_a_reused_passable_mask_is_the_fresh_one_through_a_threaded_run(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """``passable_cells`` hands a thread its last mask again once nothing holds it: every
    mask it gives, reused or new, equals the one a fresh grid would give, through a run of
    8 robots on 2 threads (a write into a mask outside its box, or a reuse while a replan
    still held it, would show here); and masks are reused."""
    from mresim_phys import Simulation
    from mresim_phys.planning import fields

    given, reused = [0], [0]
    whole_grid = fields._whole_grid

    def checked(shape: tuple[int, ...], box: tuple[int, int, int, int]) -> np.ndarray:
        held = getattr(fields._HELD, "grid", None)
        grid = whole_grid(shape, box)
        reused[0] += held is not None and held[0] is grid
        given[0] += 1
        assert not grid.any()  # what np.zeros gives, before the caller writes its box
        return grid

    monkeypatch.setattr(fields, "_whole_grid", checked)
    scenario = Path(__file__).resolve().parent.parent / "scenarios" / "11_library_8_robots.yaml"
    sim = Simulation.from_yaml(scenario, steps=40, **{"simulation.threads": 2})
    sim.run()
    assert given[0] > 40 and reused[0] > given[0] // 2
