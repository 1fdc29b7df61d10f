"""Variable terrain: the factor grid, motion on slow ground, learning it, planning on it."""

from __future__ import annotations

from collections.abc import Callable
from itertools import pairwise
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from PIL import Image

from mresim_phys.cli import main
from mresim_phys.errors import ScenarioError
from mresim_phys.knowledge.terrain import TERRAIN
from mresim_phys.planning import PLANNERS
from mresim_phys.planning.astar import AStar, weighted_astar
from mresim_phys.planning.costs import slowness_of
from mresim_phys.planning.fields import distance_field
from mresim_phys.planning.grid import SQRT2
from mresim_phys.render import Renderer
from mresim_phys.render.layers import parse_layers
from mresim_phys.sim import Simulation
from mresim_phys.strategies import Decision, RobotView
from mresim_phys.strategies.base import plan_context
from mresim_phys.types import FREE, OCCUPIED, UNKNOWN
from mresim_phys.world.element_params import TerrainSpec
from mresim_phys.world.terrain import image_factors, terrain_grid

MakeScenario = Callable[..., Path]
LEFT_ROOM_MUD = {"regions": [{"box": [0, 0, 40, 60], "factor": 0.5}]}


def one_step_east(path: Path) -> float:
    """How far robot A moves in one step along a straight path east."""
    sim = Simulation.from_yaml(path)
    robot = sim.robot("A")
    x, y = robot.position
    sim.step(actions={"A": Decision(path=np.array([[x + 15.0, y]]), goal=(x + 15.0, y))})
    return float(np.hypot(robot.position[0] - x, robot.position[1] - y))


# ---------------------------------------------------------------- the truth grid


def test_regions_give_factors_and_the_later_region_wins() -> None:
    spec = TerrainSpec.model_validate(
        {
            "regions": [
                {"box": [0, 0, 4, 4], "factor": 0.5},
                {"circle": [1, 1, 1], "factor": 0.25},
            ]
        }
    )
    grid = terrain_grid(spec, (6, 6))
    assert grid is not None and grid.dtype == np.float32
    assert grid[0, 0] == 0.25 and grid[3, 3] == 0.5 and grid[5, 5] == 1.0


def test_an_image_maps_grey_to_factor_with_a_floor(tmp_path: Path) -> None:
    values = np.array([[255, 128, 0]], dtype=np.uint8)
    Image.fromarray(values).save(tmp_path / "mud.png")
    grid = image_factors(tmp_path / "mud.png", (1, 3), min_factor=0.2)
    assert grid.tolist()[0] == pytest.approx([1.0, 128 / 255, 0.2])


def test_no_terrain_means_no_grid() -> None:
    assert terrain_grid(None, (5, 5)) is None
    assert slowness_of(None) is None
    assert slowness_of(np.ones((3, 3), dtype=np.float32)) is None  # all open: uniform


# ---------------------------------------------------------------- motion


def test_a_robot_on_half_speed_ground_moves_half_as_far(scenario_file: MakeScenario) -> None:
    plain = one_step_east(scenario_file())
    slow = one_step_east(scenario_file(terrain=LEFT_ROOM_MUD))
    assert plain == pytest.approx(2.0)  # robot A's speed
    assert slow == pytest.approx(1.0)


# ---------------------------------------------------------------- learning


def test_a_robot_learns_the_terrain_it_senses_and_nothing_else(
    scenario_file: MakeScenario,
) -> None:
    path = scenario_file(
        terrain=LEFT_ROOM_MUD, robots=[{"name": "A", "start": [8, 20], "heading_deg": 0}]
    )
    sim = Simulation.from_yaml(path)
    robot, truth = sim.robot("A"), sim.setup.terrain
    known = TERRAIN.state_of(robot.features)
    assert known is not None and truth is not None
    seen = robot.belief == FREE
    assert seen.any() and (robot.belief == UNKNOWN).any()
    assert np.array_equal(known[seen], truth[seen])
    assert (known[~seen] == 1.0).all()  # unknown ground counts as open floor


def test_the_view_carries_known_terrain_read_only(scenario_file: MakeScenario) -> None:
    sim = Simulation.from_yaml(scenario_file(terrain=LEFT_ROOM_MUD))
    known = TERRAIN.of(sim.view_of(sim.robot("A")))
    assert known is not None and not known.flags.writeable
    plain = Simulation.from_yaml(scenario_file())
    assert TERRAIN.of(plain.view_of(plain.robot("A"))) is None
    assert "terrain" not in sim.snapshot().agents[1].features  # not recorded


# ---------------------------------------------------------------- planning

MUD_ROWS, MUD_COLS = slice(0, 32), slice(25, 35)  # a slow strip with open floor below it


def open_view(terrain: np.ndarray | None, planner: str = "astar") -> RobotView:
    """A robot at the top left of a known, open 40x60 room (walls around)."""
    belief = np.full((40, 60), FREE, dtype=np.uint8)
    belief[0, :] = belief[-1, :] = belief[:, 0] = belief[:, -1] = OCCUPIED
    return RobotView(
        step=0,
        name="A",
        position=(5.5, 5.5),
        heading=0.0,
        belief=belief,
        radius=0.5,
        clearance=1.0,
        speed=1.0,
        sensor_range=10.0,
        role="explorer",
        base_position=(5.5, 5.5),
        teammates={},
        rng=np.random.default_rng(0),
        planner=PLANNERS.make(planner, {}),
        features={} if terrain is None else {"terrain": terrain},
    )


def mud(factor: float) -> np.ndarray:
    terrain = np.ones((40, 60), dtype=np.float32)
    terrain[MUD_ROWS, MUD_COLS] = factor
    return terrain


@pytest.mark.parametrize("planner", ["astar", "jps", "topological"])
def test_planners_detour_around_known_slow_ground(planner: str) -> None:
    path = plan_context(open_view(mud(0.1), planner)).plan_to(5, 54)
    assert len(path) and path[-1].tolist() == [54.5, 5.5]
    cols, rows = np.floor(path[:, 0]).astype(int), np.floor(path[:, 1]).astype(int)
    assert not ((rows < 32) & (cols >= 25) & (cols < 35)).any()


@pytest.mark.parametrize("planner", ["astar", "jps", "topological"])
def test_unknown_slow_ground_is_planned_through(planner: str) -> None:
    path = plan_context(open_view(np.ones((40, 60), dtype=np.float32), planner)).plan_to(5, 54)
    assert np.floor(path[:, 1]).max() < 10  # the straight way, through the unknown mud


def test_mildly_slow_ground_is_crossed_when_the_detour_costs_more() -> None:
    path = plan_context(open_view(mud(0.9))).plan_to(5, 54)
    assert np.floor(path[:, 1]).max() < 10


def test_the_distance_field_prices_moves_by_known_terrain() -> None:
    context = plan_context(open_view(mud(0.5)))
    plain = plan_context(open_view(None))
    assert context.slowness is not None and plain.slowness is None
    assert (
        context.field.cost_at(np.array([5]), np.array([54]))[0]
        > plain.field.cost_at(np.array([5]), np.array([54]))[0]
    )


def path_cost(path: np.ndarray, slowness: np.ndarray) -> float:
    """The terrain cost of a cell-centre path: octile moves times their cells' mean slowness."""
    cells = np.floor(path[:, ::-1]).astype(int)
    total = 0.0
    for (r0, c0), (r1, c1) in pairwise(cells):
        base = SQRT2 if r0 != r1 and c0 != c1 else 1.0
        total += base * 0.5 * (slowness[r0, c0] + slowness[r1, c1])
    return total


@pytest.mark.parametrize("seed", range(5))
def test_astar_and_the_field_agree_on_random_terrain(seed: int) -> None:
    rng = np.random.default_rng(seed)
    passable = rng.random((30, 40)) > 0.25
    passable[0, 0] = passable[29, 39] = True
    slowness = 1.0 / rng.uniform(0.1, 1.0, passable.shape)
    field = distance_field(passable, (0.5, 0.5), slowness=slowness)
    path = weighted_astar(passable, (0, 0), (29, 39), slowness)
    want = field.cost_at(np.array([29]), np.array([39]))[0]
    if not np.isfinite(want):
        assert len(path) == 0
        return
    assert path_cost(path, slowness) == pytest.approx(want)
    assert path_cost(field.path_to(29, 39), slowness) == pytest.approx(want)


def test_uniform_slowness_gives_the_uniform_costs() -> None:
    rng = np.random.default_rng(1)
    passable = rng.random((30, 40)) > 0.2
    passable[3, 3] = True
    plain = distance_field(passable, (3.5, 3.5)).costs
    ones = distance_field(passable, (3.5, 3.5), slowness=np.ones(passable.shape)).costs
    assert np.allclose(plain, ones, equal_nan=False) and np.array_equal(
        np.isinf(plain), np.isinf(ones)
    )
    assert len(AStar(AStar.Params()).plan(passable, (3.5, 3.5), (3, 3))) == 1


# ---------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    ("terrain", "field"),
    [
        ({"regions": [{"box": [0, 0, 4, 4], "factor": 0}]}, "terrain.regions[0].factor"),
        ({"regions": [{"circle": [5, 5, 3], "factor": 1.5}]}, "terrain.regions[0].factor"),
        ({"image": "mud.png", "min_factor": 0}, "terrain.min_factor"),
        ({"regions": [{"factor": 0.5}]}, "terrain.regions.0"),
        ({"regions": [], "image": "mud.png"}, "terrain"),
    ],
)
def test_bad_terrain_is_a_scenario_error_naming_the_field(
    scenario_file: MakeScenario, terrain: dict[str, Any], field: str
) -> None:
    with pytest.raises(ScenarioError, match=field.replace("[", r"\[").replace("]", r"\]")):
        Simulation.from_yaml(scenario_file(terrain=terrain))


def test_a_terrain_image_of_another_size_exits_2(
    scenario_file: MakeScenario, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = scenario_file(terrain={"image": "mud.png"})
    Image.fromarray(np.full((10, 10), 100, dtype=np.uint8)).save(tmp_path / "mud.png")
    code = main(["run", str(path), "--quiet", "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and "terrain.image" in err and "the size of the map" in err
    assert "Traceback" not in err and err.count("\n") <= 2


def test_a_relative_terrain_image_is_read_next_to_the_scenario(
    scenario_file: MakeScenario, tmp_path: Path
) -> None:
    grey = np.full((60, 80), 255, dtype=np.uint8)
    grey[:, :40] = 51  # factor 0.2
    Image.fromarray(grey).save(tmp_path / "mud.png")
    sim = Simulation.from_yaml(scenario_file(terrain={"image": "mud.png"}))
    assert sim.setup.terrain is not None
    assert sim.setup.terrain[10, 10] == pytest.approx(0.2)


# ---------------------------------------------------------------- videos


def test_slow_ground_is_tinted_brown_in_frames(scenario_file: MakeScenario) -> None:
    snap = Simulation.from_yaml(scenario_file(terrain=LEFT_ROOM_MUD)).snapshot()
    assert snap.terrain is not None
    shaded = Renderer(snap.truth.shape, parse_layers("default"), 8).render(snap)
    plain = Renderer(snap.truth.shape, parse_layers("-terrain"), 8).render(snap)
    assert not np.array_equal(shaded, plain)
    left, right = np.s_[100:200, 60:100], np.s_[100:200, 400:440]  # 8 px per cell
    assert np.array_equal(shaded[right], plain[right])
    tinted = shaded[left].astype(int)
    assert (tinted[..., 2] > tinted[..., 0]).mean() > 0.9  # red over blue: brown (not glyphs)
