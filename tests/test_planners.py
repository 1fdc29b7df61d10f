"""Phase 4b planners: A*, jump point search, the topological map, smoothing, YAML selection."""

from __future__ import annotations

from collections.abc import Callable
from itertools import pairwise
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.sparse.csgraph import dijkstra
from shapely.geometry import LineString, box
from shapely.ops import unary_union
from test_planning import assert_valid_path, random_passable, reference_dijkstra

from mresim_phys import Simulation
from mresim_phys.cli import main
from mresim_phys.errors import ScenarioError, UnknownPluginError
from mresim_phys.planning import BUILT_IN, PLANNERS, Planner, topocorridor, topological
from mresim_phys.planning.astar import AStar, astar_search
from mresim_phys.planning.fields import distance_field, path_length, traversable
from mresim_phys.planning.grid import Window
from mresim_phys.planning.jps import JumpPointSearch, jps_search
from mresim_phys.planning.params import PlannerParams, TopologicalParams
from mresim_phys.planning.skeleton import removal_table, thin
from mresim_phys.planning.smoothing import smooth_path
from mresim_phys.planning.topobuild import build_map
from mresim_phys.planning.topocache import MapCache
from mresim_phys.planning.topological import TopologicalPlanner
from mresim_phys.scenario.readers import load_image_map, load_ros_map, load_text_map
from mresim_phys.strategies import RobotView, plan_context
from mresim_phys.strategies.frontier import FrontierExploration
from mresim_phys.strategies.params import FrontierParams
from mresim_phys.types import FREE, OCCUPIED, UNKNOWN

SEEDS = st.integers(0, 2**32 - 1)
MAPS = Path(__file__).parent.parent / "maps"


def two_cells(passable: np.ndarray, seed: int) -> tuple[tuple[int, int], tuple[int, int]] | None:
    rr, cc = np.nonzero(passable)
    if len(rr) == 0:
        return None
    i, j = np.random.default_rng(seed + 7).integers(len(rr), size=2)
    return (int(rr[i]), int(cc[i])), (int(rr[j]), int(cc[j]))


def centre(rc: tuple[int, int]) -> tuple[float, float]:
    return rc[1] + 0.5, rc[0] + 0.5


def check_optimal(
    planner: Planner, passable: np.ndarray, start: tuple[int, int], goal: tuple[int, int]
) -> None:
    path = planner.plan(passable, centre(start), goal)
    expected = reference_dijkstra(passable, start)[goal]
    if not np.isfinite(expected):
        assert path.shape == (0, 2)
        return
    assert_valid_path(path, passable)
    np.testing.assert_allclose(path[[0, -1]], [centre(start), centre(goal)])
    assert path_length(path) == pytest.approx(expected, abs=1e-9)


# --------------------------------------------------------------------------- registry


def test_registry_holds_the_built_ins() -> None:
    assert set(BUILT_IN) <= set(PLANNERS.names())
    for name in BUILT_IN:
        cls = PLANNERS.get(name)
        assert isinstance(cls(cls.Params()), Planner)


def test_unknown_planner_lists_close_matches() -> None:
    with pytest.raises(UnknownPluginError, match="'jps'"):
        PLANNERS.get("jsp")


# --------------------------------------------------------------------------- A* and JPS


@settings(max_examples=200, deadline=None)
@given(seed=SEEDS, rows=st.integers(2, 16), cols=st.integers(2, 16))
def test_astar_and_jps_lengths_equal_reference_dijkstra(seed: int, rows: int, cols: int) -> None:
    passable = random_passable(seed, (rows, cols))
    ends = two_cells(passable, seed)
    if ends is None:
        return
    for planner in (AStar(PlannerParams()), JumpPointSearch(PlannerParams())):
        check_optimal(planner, passable, *ends)


@pytest.mark.parametrize("cls", [AStar, JumpPointSearch, TopologicalPlanner])
def test_unreachable_or_blocked_goals_give_an_empty_path(cls: type) -> None:
    passable = np.ones((20, 30), dtype=bool)
    passable[:, 14:16] = False  # a wall splits the grid in two
    planner = cls(cls.Params())
    assert planner.plan(passable, (3.5, 3.5), (10, 25)).shape == (0, 2)
    assert planner.plan(passable, (3.5, 3.5), (10, 14)).shape == (0, 2)  # goal in the wall
    assert planner.plan(passable, (3.5, 3.5), (40, 3)).shape == (0, 2)  # goal off the grid
    assert len(planner.plan(passable, (3.5, 3.5), (10, 10))) > 0


def test_diagonal_squeeze_between_two_blocked_cells_is_forbidden() -> None:
    passable = np.array([[1, 0, 1], [0, 1, 1], [1, 1, 1]], dtype=bool)
    passable[0, 2] = False
    for cls in (AStar, JumpPointSearch):
        path = cls(PlannerParams()).plan(passable, (0.5, 0.5), (1, 1))
        assert path.shape == (0, 2)  # (0, 0) -> (1, 1) squeezes between (0, 1) and (1, 0)


def open_grid(size: int = 200) -> np.ndarray:
    passable = np.ones((size, size), dtype=bool)
    rng = np.random.default_rng(5)
    for r, c in rng.integers(10, size - 20, size=(12, 2)):
        passable[r : r + 6, c : c + 6] = False
    return passable


def test_jps_expands_far_fewer_nodes_than_astar_in_open_space() -> None:
    passable = open_grid()
    window = Window.of(passable)
    assert window is not None
    a_path, a_count = astar_search(window, (1, 1), (198, 190))
    j_path, j_count = jps_search(window, (1, 1), (198, 190))
    assert path_length(j_path) == pytest.approx(path_length(a_path), abs=1e-9)
    assert j_count * 5 < a_count


# --------------------------------------------------------------------------- topological


def known_truth(occupied: np.ndarray, clearance: float = 3.0) -> np.ndarray:
    return traversable(np.where(occupied, OCCUPIED, FREE).astype(np.uint8), clearance)


@settings(max_examples=60, deadline=None)
@given(seed=SEEDS, spacing=st.integers(2, 6), flips=st.integers(0, 30))
def test_topological_paths_stay_on_passable_cells_even_on_a_stale_map(
    seed: int, spacing: int, flips: int
) -> None:
    rng = np.random.default_rng(seed)
    belief = rng.choice([UNKNOWN, FREE, FREE, FREE, OCCUPIED], size=(24, 24)).astype(np.uint8)
    built_from = traversable(belief, 0.0)
    cells = rng.integers(0, 24, size=(flips, 2))
    belief[cells[:, 0], cells[:, 1]] = rng.choice([FREE, OCCUPIED, UNKNOWN], size=flips)
    passable = traversable(belief, 0.0)
    ends = two_cells(passable, seed)
    if ends is None:
        return
    params = TopologicalParams(node_spacing=spacing, rebuild_fraction=1.0)
    planner = TopologicalPlanner(params, MapCache())
    planner.map = build_map(built_from, spacing)  # as if built before the map changed
    path = planner.plan(passable, centre(ends[0]), ends[1])
    optimal = reference_dijkstra(passable, ends[0])[ends[1]]
    assert (len(path) > 0) == bool(np.isfinite(optimal))
    if len(path):
        assert_valid_path(path, passable)
        cells_rc = np.floor(path[:, ::-1]).astype(int)
        assert (belief[cells_rc[:, 0], cells_rc[:, 1]] == FREE).all()
        assert path_length(path) >= optimal - 1e-9


def test_regions_are_geodesic_a_wall_never_joins_two_rooms() -> None:
    """A narrow room beside a wide one: by straight-line distance the wide room's cells
    along the wall are nearer the narrow room's nodes; along free space they are not."""
    occupied = np.zeros((40, 80), dtype=bool)
    occupied[:, 11] = True  # a one-cell wall; the door is far away, at the bottom
    occupied[34:, 11] = False
    passable = known_truth(occupied, clearance=0.5)
    topo = build_map(passable, spacing=8)
    left = set(np.unique(topo.labels[:20, :11]).tolist()) - {-1}
    right = set(np.unique(topo.labels[:20, 12:]).tolist()) - {-1}
    assert left and right and not (left & right)
    graph = topo.graph.tocoo()
    assert not any(a in left and b in right for a, b in zip(graph.row, graph.col, strict=True))
    assert ((topo.labels >= 0) == passable).all()  # every passable cell has a node
    assert topo.skeleton[topo.nodes_rc[:, 0], topo.nodes_rc[:, 1]].all()


def full_scan_zhang_suen(mask: np.ndarray) -> np.ndarray:
    """Reference thinning: every pixel re-examined in every subiteration (numpy)."""
    img = np.pad(mask, 1).astype(np.uint8)
    table = removal_table()
    changed = True
    while changed:
        changed = False
        for bit in (1, 2):
            code = (img[:-2, :-2] + 2 * img[:-2, 1:-1] + 4 * img[:-2, 2:] + 8 * img[1:-1, 2:]
                    + 16 * img[2:, 2:] + 32 * img[2:, 1:-1] + 64 * img[2:, :-2]
                    + 128 * img[1:-1, :-2])  # fmt: skip
            remove = img[1:-1, 1:-1].astype(bool) & ((table[code] & bit) > 0)
            if remove.any():
                img[1:-1, 1:-1][remove] = 0
                changed = True
    return img[1:-1, 1:-1].astype(bool)


@settings(max_examples=100, deadline=None)
@given(seed=SEEDS, rows=st.integers(1, 40), cols=st.integers(1, 40))
def test_skeleton_equals_full_scan_zhang_suen(seed: int, rows: int, cols: int) -> None:
    rng = np.random.default_rng(seed)
    mask = rng.random((rows, cols)) > rng.uniform(0.0, 0.6)
    if rng.random() < 0.5:  # blobs as well as noise
        mask = traversable(np.where(mask, FREE, OCCUPIED).astype(np.uint8), 1.2)
    skeleton = thin(mask)
    assert np.array_equal(skeleton, full_scan_zhang_suen(mask))
    assert not (skeleton & ~mask).any()


def test_skeleton_of_a_corridor_is_its_centre_line() -> None:
    mask = np.zeros((11, 60), dtype=bool)
    mask[3:8, 2:58] = True
    skeleton = thin(mask)
    assert skeleton[5, 6:54].all() and skeleton.sum() < 60


def shipped_truths() -> dict[str, np.ndarray]:
    return {
        "office": load_image_map(MAPS / "office.png").occupied,
        "maze": load_image_map(MAPS / "maze.png").occupied,
        "rubble": load_image_map(MAPS / "rubble.png").occupied,
        "small_rooms": load_image_map(MAPS / "small_rooms.png").occupied,
        "cave": load_text_map(MAPS / "cave.txt").occupied,
        "warehouse": load_ros_map(MAPS / "warehouse.yaml").occupied,
    }


@pytest.mark.parametrize("name", ["office", "maze", "rubble", "small_rooms", "cave", "warehouse"])
def test_topological_paths_are_within_15_percent_of_optimal_on_shipped_maps(
    name: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    def no_fallback(*args: object) -> None:
        raise AssertionError("on a fresh map the corridor must hold the path")

    monkeypatch.setattr(topological, "astar_search", no_fallback)
    passable = known_truth(shipped_truths()[name])
    planner = TopologicalPlanner(TopologicalParams(), MapCache())
    rows, cols = np.nonzero(passable)
    rng = np.random.default_rng(1)
    for _ in range(12):
        i, j = rng.integers(len(rows), size=2)
        start, goal = (int(rows[i]), int(cols[i])), (int(rows[j]), int(cols[j]))
        optimal = distance_field(passable, centre(start)).costs[goal]
        path = planner.plan(passable, centre(start), goal)
        assert (len(path) > 0) == bool(np.isfinite(optimal))
        if len(path) > 1:
            assert_valid_path(path, passable)
            assert optimal - 1e-9 <= path_length(path) <= 1.15 * optimal


def test_topological_queries_agree_however_freshness_is_known_and_however_wide_the_ring(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The corridor search reads the build's own padded mask when the map is fresh, or a
    padded copy of the mask given (plus the cells in no region) otherwise; both give the
    same path on a fresh map, as does a search whose bands outgrow the ring."""
    passable = known_truth(shipped_truths()["office"])
    topo = build_map(passable, 10)
    rows, cols = np.nonzero(passable)
    rng = np.random.default_rng(3)
    for _ in range(6):
        i, j = rng.integers(len(rows), size=2)
        start, goal = (int(rows[i]), int(cols[i])), (int(rows[j]), int(cols[j]))
        expected = topological.topological_path(topo, passable, start, goal, 1, True)
        assert len(expected) > 0
        for fresh in (None, False):
            got = topological.topological_path(topo, passable.copy(), start, goal, 1, fresh)
            np.testing.assert_array_equal(got, expected)
        monkeypatch.setattr(topocorridor._WORK, "ring", np.empty((3, 2), dtype=np.int32))
        got = topological.topological_path(topo, passable, start, goal, 1, True)
        np.testing.assert_array_equal(got, expected)
        assert topocorridor._WORK.ring.shape[1] > 2


def test_graph_routes_cost_what_scipy_dijkstra_finds() -> None:
    passable = known_truth(shipped_truths()["rubble"])
    topo = build_map(passable, 10)
    rng = np.random.default_rng(4)
    for a in rng.integers(topo.node_count, size=5):
        costs = dijkstra(topo.graph, indices=int(a))
        for b in rng.integers(topo.node_count, size=10):
            nodes, cost = topo.route(int(a), int(b))
            assert cost == pytest.approx(costs[b], abs=1e-9)
            assert nodes[0] == a and nodes[-1] == b
            steps = [topo.graph[u, v] for u, v in pairwise(nodes)]
            assert sum(steps) == pytest.approx(cost, abs=1e-9)


def test_maps_are_rebuilt_only_when_changed_enough_and_shared() -> None:
    passable = known_truth(shipped_truths()["small_rooms"])
    cache = MapCache()
    first = TopologicalPlanner(TopologicalParams(rebuild_fraction=0.05), cache)
    second = TopologicalPlanner(TopologicalParams(rebuild_fraction=0.05), cache)
    first.plan(passable, (66.5, 52.5), (60, 94))
    second.plan(passable.copy(), (94.5, 68.5), (52, 66))
    assert cache.builds == 1 and first.map is second.map
    changed = passable.copy()
    changed[np.nonzero(passable)[0][:50], np.nonzero(passable)[1][:50]] = False  # < 5 %
    first.plan(changed, (66.5, 52.5), (60, 94))
    assert cache.builds == 1
    changed[:, :40] = False  # far more than 5 %
    first.plan(changed, (66.5, 52.5), (60, 94))
    assert cache.builds == 2 and first.map is not second.map


def test_topological_skeleton_reaches_the_decision_info() -> None:
    belief = np.full((40, 100), OCCUPIED, dtype=np.uint8)
    belief[5:35, 5:95] = FREE
    belief[5:35, 80:95] = UNKNOWN
    planner = TopologicalPlanner(TopologicalParams(node_spacing=6), MapCache())
    view = RobotView(
        step=10, name="A", position=(10.5, 20.5), heading=0.0, belief=belief, radius=1.0,
        clearance=2.0, speed=2.0, sensor_range=30.0, role="explorer",
        base_position=(10.5, 20.5), teammates={}, rng=np.random.default_rng(0), planner=planner,
    )  # fmt: skip
    decision = FrontierExploration(FrontierParams()).decide(view)
    assert len(decision.path) > 0
    skeleton = decision.info["skeleton"]
    assert skeleton.shape == belief.shape and skeleton.any()
    assert (belief[skeleton] == FREE).all()


def test_the_frontier_strategy_follows_its_planners_path() -> None:
    belief = np.full((40, 100), OCCUPIED, dtype=np.uint8)
    belief[5:35, 5:95] = FREE
    belief[28:35, 60:95] = UNKNOWN  # the only frontier: down and to the right of the robot
    view = RobotView(
        step=10, name="A", position=(10.5, 8.5), heading=0.0, belief=belief, radius=1.0,
        clearance=2.0, speed=2.0, sensor_range=30.0, role="explorer",
        base_position=(10.5, 8.5), teammates={}, rng=np.random.default_rng(0),
    )  # fmt: skip
    plain = FrontierExploration(FrontierParams()).decide(view)
    smooth = AStar(PlannerParams(smooth=True))
    decision = FrontierExploration(FrontierParams()).decide(
        RobotView(**{**view.__dict__, "planner": smooth})
    )
    assert decision.goal == plain.goal and decision.goal is not None
    np.testing.assert_allclose(decision.path[[0, -1]], plain.path[[0, -1]])
    assert len(decision.path) < len(plain.path) / 5  # straight across the open room
    assert path_length(decision.path) < path_length(plain.path) - 1.0


def test_strategies_get_the_topological_map_with_or_without_that_planner() -> None:
    belief = np.full((40, 60), OCCUPIED, dtype=np.uint8)
    belief[15:25, 2:58] = FREE  # two crossing corridors: a junction where they meet
    belief[2:38, 25:35] = FREE
    view = RobotView(
        step=10, name="A", position=(10.5, 20.5), heading=0.0, belief=belief, radius=1.0,
        clearance=2.0, speed=2.0, sensor_range=30.0, role="relay",
        base_position=(10.5, 20.5), teammates={}, rng=np.random.default_rng(0),
    )  # fmt: skip
    topo = plan_context(view).topology(spacing=6)
    assert topo.node_count > 2 and len(topo.junctions) > 0
    assert topo.skeleton[topo.junctions[:, 0], topo.junctions[:, 1]].all()
    assert (np.abs(topo.junctions - [20, 30]) <= 3).all()  # only at the crossing
    planner = TopologicalPlanner(TopologicalParams(node_spacing=6), MapCache())
    mine = plan_context(RobotView(**{**view.__dict__, "planner": planner})).topology()
    assert mine is planner.map and mine is not None


# --------------------------------------------------------------------------- smoothing


@settings(max_examples=80, deadline=None)
@given(seed=SEEDS, radius=st.floats(0.5, 2.0))
def test_smoothed_paths_never_clip_a_known_obstacle_or_enter_unknown(
    seed: int, radius: float
) -> None:
    rng = np.random.default_rng(seed)
    belief = rng.choice([FREE] * 12 + [OCCUPIED, UNKNOWN], size=(30, 30)).astype(np.uint8)
    passable = traversable(belief, radius + 0.75)
    ends = two_cells(passable, seed)
    if ends is None:
        return
    raw = AStar(PlannerParams()).plan(passable, centre(ends[0]), ends[1])
    path = AStar(PlannerParams(smooth=True)).plan(passable, centre(ends[0]), ends[1])
    assert len(path) == len(raw) == 0 or path_length(path) <= path_length(raw) + 1e-9
    if len(path) < 2:
        return
    np.testing.assert_allclose(path[[0, -1]], raw[[0, -1]])
    line = LineString(path)
    walls = unary_union([box(c, r, c + 1, r + 1) for r, c in np.argwhere(belief == OCCUPIED)])
    unknown = unary_union([box(c, r, c + 1, r + 1) for r, c in np.argwhere(belief == UNKNOWN)])
    assert line.distance(walls) >= radius - 1e-9
    assert line.intersection(unknown).length < 1e-9


def test_smoothing_takes_shortcuts_in_open_space() -> None:
    passable = np.ones((30, 30), dtype=bool)
    raw = AStar(PlannerParams()).plan(passable, (1.5, 1.5), (20, 27))
    smooth = smooth_path(raw, passable)
    assert len(smooth) == 2
    assert path_length(smooth) == pytest.approx(np.hypot(26, 19))


# --------------------------------------------------------------------------- YAML


def test_planners_are_chosen_per_robot_in_yaml(scenario_file: Callable[..., Path]) -> None:
    team = {"speed": 2, "radius": 1.0, "sensor": {"range": 30}, "comm_range": 20, "planner": "jps"}
    robots = [
        {"name": "A", "start": [8, 20]},
        {
            "name": "B",
            "start": [8, 40],
            "planner": {"name": "topological", "params": {"node_spacing": 6}},
        },
    ]
    sim = Simulation.from_yaml(scenario_file(team=team, robots=robots, steps=30))
    a, b = sim.robot("A").planner, sim.robot("B").planner
    assert isinstance(a, JumpPointSearch) and isinstance(b, TopologicalPlanner)
    assert b.params.node_spacing == 6
    sim.run()
    assert b.map is not None and sim.robot("B").distance > 0
    assert sim.robot("B").decision is not None and "skeleton" in sim.robot("B").decision.info


def test_bad_planner_params_name_the_field(scenario_file: Callable[..., Path]) -> None:
    robots = [
        {
            "name": "A",
            "start": [8, 20],
            "planner": {"name": "topological", "params": {"node_spacin": 5}},
        }
    ]
    with pytest.raises(ScenarioError, match=r"robots\[0\]\.planner\.params.*'node_spacing'"):
        Simulation.from_yaml(scenario_file(robots=robots))


def test_validate_rejects_an_unknown_planner_with_a_close_match(
    scenario_file: Callable[..., Path], capsys: pytest.CaptureFixture[str]
) -> None:
    path = scenario_file(team={"planner": "topologcal"})
    assert main(["validate", str(path)]) != 0
    err = capsys.readouterr().err
    assert "team.planner" in err and "'topological'" in err
