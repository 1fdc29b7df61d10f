"""Goal costs that stop at one goal (planning/goals.py) agree with the full distance field."""

from __future__ import annotations

import numpy as np
import pytest
from test_planning import random_passable, random_start

from mresim_phys.planning.fields import distance_field
from mresim_phys.planning.goals import goal_costs
from mresim_phys.planning.grid import bbox


@pytest.mark.parametrize("seed", range(40))
@pytest.mark.parametrize("limit", [6.0, 15.5, np.inf])
def test_goal_costs_are_the_fields_costs_or_bounded_below(seed: int, limit: float) -> None:
    passable = random_passable(seed, (30, 40))
    start = random_start(passable, seed)
    if start is None:
        return
    rng = np.random.default_rng(seed + 7)
    goals = np.column_stack((rng.integers(0, 30, 6), rng.integers(0, 40, 6)))
    xy = (start[1] + 0.5, start[0] + 0.5)
    full = distance_field(passable, xy, limit=limit).cost_at(goals[:, 0], goals[:, 1])
    for wanted in range(len(goals)):
        got = goal_costs(passable, xy, goals, wanted, limit, bbox(passable))
        assert got is not None
        known = np.isfinite(got.found)
        assert np.array_equal(got.found[known], full[known])  # the same floats, bit for bit
        assert np.isfinite(full[wanted]) == known[wanted]  # the wanted goal is always settled
        unknown = ~known
        if got.floor == np.inf:
            assert np.all(full[unknown] == np.inf)
        else:  # every goal left unknown costs at least the floor (without a limit: truly)
            exact = distance_field(passable, xy).cost_at(goals[:, 0], goals[:, 1])
            assert np.all(exact[unknown] >= got.floor)


def test_goal_costs_of_a_start_off_the_map_is_none() -> None:
    passable = np.zeros((10, 10), dtype=bool)
    passable[1, 1] = True
    goals = np.array([[1, 1]])
    assert goal_costs(passable, (8.5, 8.5), goals, 0, np.inf, bbox(passable)) is None
