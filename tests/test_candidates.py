"""Phase 4 (decide): which frontiers enter the auction (``FrontierParams.candidate_power``).

The best ``max_frontiers`` by ``size / d^power``: 4 by the auction's own utility (the
default), 1 as the original orders them (area / distance), so a far large frontier enters
the auction beside the near small ones, 2 between. A search bounded by a horizon must
settle on the candidates a whole-map search would give, for every power.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

from mresim_phys.errors import ScenarioError
from mresim_phys.knowledge.frontiers import Frontiers
from mresim_phys.scenario.load import validate_scenario
from mresim_phys.strategies.frontier import FrontierExploration
from mresim_phys.strategies.params import FrontierParams
from mresim_phys.strategies.parts import UtilityRanking

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"


def clusters(sizes: list[int]) -> Frontiers:
    """Frontier clusters of these sizes (the ranking reads only their sizes)."""
    k = len(sizes)
    return Frontiers(
        sizes=np.array(sizes, dtype=np.intp),
        centroids=np.zeros((k, 2)),
        cells_rc=np.zeros((k, 2), dtype=np.intp),
        cluster_of=np.arange(k, dtype=np.intp),
    )


def ranking(power: int) -> UtilityRanking:
    strategy = FrontierExploration(FrontierParams(candidate_power=power))
    assert isinstance(strategy.parts.ranking, UtilityRanking)
    return strategy.parts.ranking


def test_the_original_order_lets_a_far_wing_into_the_auction() -> None:
    """Six 3-cell doorways 10 cells away and an unvisited wing of 5,000 cells 100 cells
    away: by size / d^4 the wing is not among the six best, by size / d^2 (the default)
    or size / d it is first."""
    frontiers = clusters([3] * 6 + [5000])
    costs = np.array([10.0] * 6 + [100.0])
    assert 6 not in ranking(4).candidates(frontiers, costs)
    assert ranking(2).candidates(frontiers, costs)[0] == 6
    assert ranking(1).candidates(frontiers, costs)[0] == 6
    assert FrontierParams().candidate_power == 2


def test_an_unreachable_frontier_is_never_a_candidate() -> None:
    frontiers = clusters([9000, 3, 4])
    costs = np.array([np.inf, 10.0, 20.0])
    for power in (1, 2, 3, 4):
        assert 0 not in ranking(power).candidates(frontiers, costs)


@settings(max_examples=200, deadline=None)
@given(
    sizes=st.lists(st.integers(1, 5000), min_size=1, max_size=30),
    seed=st.integers(0, 2**32 - 1),
    limit=st.floats(2.0, 400.0),
    power=st.integers(1, 4),
)
def test_a_settled_horizon_gives_the_whole_map_s_candidates(
    sizes: list[int], seed: int, limit: float, power: int
) -> None:
    """A search out to ``limit`` knows the costs up to it (those beyond are at least
    ``limit``): once the ranking calls it settled, its candidates are the whole map's."""
    rng = np.random.default_rng(seed)
    costs = rng.uniform(1.0, 500.0, len(sizes))
    frontiers = clusters(sizes)
    seen = np.where(costs <= limit, costs, np.inf)
    rank = ranking(power)
    found = rank.candidates(frontiers, seen)
    if len(found) and rank.settled(frontiers, seen, found, limit):
        assert found.tolist() == rank.candidates(frontiers, costs).tolist()


def test_a_scenario_sets_the_power_and_one_out_of_range_is_refused() -> None:
    path = SCENARIOS / "13_rooms_4_robots.yaml"
    data = yaml.safe_load(path.read_text())
    data["team"]["strategy"] = {"name": "frontier", "params": {"candidate_power": 2}}
    validate_scenario(data, str(path))
    for wrong in (0, 5, "two"):
        data["team"]["strategy"]["params"]["candidate_power"] = wrong
        with pytest.raises(ScenarioError, match="candidate_power"):
            validate_scenario(data, str(path))
