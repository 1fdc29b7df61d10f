"""``hungarian`` and ``min_pos``: frontier exploration with a team assignment rule."""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest

from mresim_phys.knowledge.teammates import TeammateInfo
from mresim_phys.sim import Simulation
from mresim_phys.strategies import STRATEGIES, RobotView
from mresim_phys.strategies.assignment import (
    HungarianExploration,
    MinPosExploration,
    assign,
    min_pos_choice,
)
from mresim_phys.strategies.params import HungarianParams, MinPosParams
from mresim_phys.types import FREE, OCCUPIED, UNKNOWN

ROOT = Path(__file__).resolve().parent.parent


def brute_force(costs: np.ndarray) -> float:
    """The least total cost of giving every row a distinct column (rows <= columns)."""
    rows, cols = costs.shape
    return min(
        sum(costs[r, c] for r, c in enumerate(perm))
        for perm in itertools.permutations(range(cols), rows)
    )


@pytest.mark.parametrize("seed", range(20))
def test_the_assignment_is_optimal_as_brute_force_on_4x4(seed: int) -> None:
    costs = np.random.default_rng(seed).integers(1, 50, (4, 4)).astype(float)
    columns = assign(costs)
    assert sorted(columns.tolist()) == [0, 1, 2, 3]
    assert sum(costs[r, c] for r, c in enumerate(columns)) == brute_force(costs)


def test_more_robots_than_frontiers_leaves_some_unassigned() -> None:
    costs = np.array([[1.0, 9.0], [2.0, 1.0], [1.5, 1.2]])
    columns = assign(costs)
    assert sorted(c for c in columns.tolist() if c >= 0) == [0, 1]
    assert (columns == -1).sum() == 1


def test_min_pos_takes_the_frontier_where_fewest_teammates_are_nearer() -> None:
    mine = np.array([10.0, 30.0, 50.0])
    others = np.array([[5.0, 40.0, 45.0], [8.0, 20.0, 60.0]])  # both nearer to frontier 0
    ahead = np.array([0, 0])
    # ranks: frontier 0: 2, frontier 1: 1, frontier 2: 1 -> the nearer of 1 and 2
    assert min_pos_choice(mine, others, ahead) == 1
    assert min_pos_choice(mine, others[:0], ahead[:0]) == 0  # alone: the nearest
    tie = np.array([[10.0, 99.0, 99.0]])
    assert min_pos_choice(mine, tie, np.array([1])) == 1  # a tie lost to a higher rank
    assert min_pos_choice(mine, tie, np.array([0])) == 0
    assert min_pos_choice(np.full(3, np.inf), others, ahead) == -1


def corridor_view(
    teammates: dict[str, TeammateInfo], lost: frozenset[str] = frozenset()
) -> RobotView:
    """A 20x100 known corridor, unknown at both ends; robot A in the middle, a bit left."""
    belief = np.full((20, 100), OCCUPIED, dtype=np.uint8)
    belief[5:15, :] = UNKNOWN
    belief[5:15, 20:80] = FREE
    return RobotView(
        step=10, name="A", position=(45.5, 10.5), heading=0.0, belief=belief, radius=1.0,
        clearance=2.0, speed=2.0, sensor_range=30.0, role="explorer",
        base_position=(50.5, 10.5), teammates=teammates, rng=np.random.default_rng(0),
        features={"lost": lost}, team_order=("A", "B"), vary_with_seed=False,
    )  # fmt: skip


STRATEGY_CASES = [
    (HungarianExploration, HungarianParams),
    (MinPosExploration, MinPosParams),
]


@pytest.mark.parametrize(("cls", "params"), STRATEGY_CASES)
def test_a_teammate_nearer_the_left_frontier_sends_this_robot_right(
    cls: type, params: type
) -> None:
    mate = TeammateInfo("B", (25.5, 10.5), None, "active", "explorer", step=9)
    alone = cls(params()).decide(corridor_view({}))
    assert alone.goal is not None and alone.goal[0] < 50  # the nearer, left frontier
    shared = cls(params()).decide(corridor_view({"B": mate}))
    assert shared.goal is not None and shared.goal[0] > 50


@pytest.mark.parametrize(("cls", "params"), STRATEGY_CASES)
def test_a_presumed_lost_teammate_takes_no_frontier(cls: type, params: type) -> None:
    mate = TeammateInfo("B", (25.5, 10.5), None, "active", "explorer", step=9)
    decision = cls(params()).decide(corridor_view({"B": mate}, lost=frozenset({"B"})))
    assert decision.goal is not None and decision.goal[0] < 50


@pytest.mark.parametrize("name", ["hungarian", "min_pos"])
def test_the_strategies_are_registered_and_explore_a_small_map(name: str) -> None:
    assert STRATEGIES.get(name).name == name
    path = ROOT / "scenarios" / "06_small_rooms_random_walk.yaml"
    sim = Simulation.from_yaml(path, steps=400, **{"team.strategy": name})
    record = sim.run()
    assert record.explored > 0.9
