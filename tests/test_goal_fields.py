"""Phase 4 (decide): the frontier auction's searches from its goals (planning/goal_fields.py).

A search from a goal bounds every teammate's path cost to it at once; the auction fixes a
pair on those bounds only when they tell it from every other pair, and otherwise searches
exactly. The bounds must hold for every teammate, and the winner must be the one the
teammates' own searches give, ties included.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from test_frontiers import random_belief

from mresim_phys.planning.fields import distance_field, snap_to_passable, traversable
from mresim_phys.planning.goal_fields import GoalFields, standing_cells
from mresim_phys.planning.goals import goal_costs
from mresim_phys.planning.grid import bbox
from mresim_phys.strategies.auction import Bidder, TeammateSearches, greedy_auction
from mresim_phys.strategies.base import PlanContext


def scene(seed: int, mates: int, shape: tuple[int, int] = (40, 48)) -> Any:
    """A random passable map, goal cells on it and teammates on it (some on one cell, some
    off the passable cells); None where the map has too few passable cells."""
    passable = traversable(random_belief(seed, shape), 0.8)
    cells = np.argwhere(passable)
    if len(cells) < 4:
        return None
    rng = np.random.default_rng(seed)
    goals = cells[rng.choice(len(cells), 4)]
    picked = cells[rng.choice(len(cells), mates)] + rng.uniform(0.0, 1.0, (mates, 2))
    anywhere = rng.uniform((-2.0, -2.0), (shape[0] + 2.0, shape[1] + 2.0), (mates, 2))
    where = np.where(rng.random((mates, 1)) < 0.8, picked, anywhere)
    where[1::3] = where[0] if mates else where[1::3]  # teammates sharing a spot: equal costs
    positions = [(float(rc[1]), float(rc[0])) for rc in where]
    return passable, goals, positions


def forward(passable: np.ndarray, position: tuple[float, float], goals: np.ndarray) -> Any:
    """A teammate's exact path costs to the goals (its own search)."""
    return distance_field(passable, position).cost_at(goals[:, 0], goals[:, 1])


def fields_with_exact_costs(seed: int, shape: tuple[int, int] = (40, 48)) -> Any:
    """A :func:`scene`'s goal searches for its 7 teammates and each teammate's exact costs
    to the goals (rows: teammates); None where the map has too few passable cells."""
    found = scene(seed, 7, shape)
    if found is None:
        return None
    passable, goals, positions = found
    box = bbox(passable)
    assert box is not None
    fields = GoalFields(passable, box, goals, standing_cells(passable, positions))
    return fields, np.array([forward(passable, xy, goals) for xy in positions])


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), limits=st.lists(st.floats(1.0, 80.0), max_size=4))
def test_a_goals_search_bounds_every_teammates_exact_cost(seed: int, limits: list[float]) -> None:
    """Paused at any cost, grown to any window, then run until a teammate is reached: each
    teammate's exact cost stays within its bounds, within rounding where the search reached
    it, and a cost the search calls unreachable is."""
    made = fields_with_exact_costs(seed)
    if made is None:
        return
    fields, exact = made  # exact: a row per teammate, a column per goal
    cells = fields.cells
    low = np.zeros_like(exact)  # every bound starts at zero, as loose as it gets
    high = np.full_like(exact, np.inf)
    known = np.zeros(exact.shape, dtype=bool)
    has_cell = cells[:, 0] >= 0
    for step, limit in enumerate([*sorted(limits), np.inf]):
        fields.tighten(step % exact.shape[1], step % exact.shape[0], limit, low, high, known)
        assert np.all(low[has_cell] <= exact[has_cell])
        assert np.all(exact[has_cell] <= high[has_cell])
        reached = np.isfinite(high)
        assert np.all(high[reached] - low[reached] < 1e-6)
        assert np.all(exact[known] == np.inf)
        assert not known[~has_cell].any() and np.all(low[~has_cell] == 0.0)
    for who in np.flatnonzero(has_cell):  # unbounded: it runs until who is known
        fields.tighten(1, int(who), np.inf, low, high, known)
        assert np.isfinite(high[who, 1]) != known[who, 1]
        assert known[who, 1] == (exact[who, 1] == np.inf)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_teammates_stand_where_their_own_searches_start(seed: int) -> None:
    found = scene(seed, 9)
    if found is None:
        return
    passable, _, positions = found
    for xy, cell in zip(positions, standing_cells(passable, positions), strict=True):
        snapped = snap_to_passable(passable, xy, 3.0)
        assert tuple(cell) == ((-1, -1) if snapped is None else snapped)


def context_of(passable: np.ndarray) -> PlanContext:
    """A planning context that holds only a passable map (what the teammates' searches read)."""
    context = PlanContext.__new__(PlanContext)
    context.__dict__["_passable"] = (passable, bbox(passable))
    context.__dict__["slowness"] = None
    return context


def run_auction(seed: int, mates: int, with_fields: bool, counted: list[Any]) -> int:
    found = scene(seed, mates)
    assert found is not None
    passable, goals, positions = found
    rng = np.random.default_rng(seed + 1)
    sizes = rng.choice([4.0, 9.0, 30.0], len(goals))  # equal sizes: ties between frontiers
    me = positions[0]
    mine = forward(passable, me, goals)
    bidders = [Bidder("me", mine, np.ones(len(goals), dtype=bool), me, rank=mates)]
    ranks = rng.permutation(mates)
    bidders += [
        Bidder.estimated(f"m{i}", xy, goals, int(ranks[i])) for i, xy in enumerate(positions)
    ]
    fields = None
    if with_fields:
        fields = GoalFields.for_auction(passable, bbox(passable), goals, positions)  # type: ignore[arg-type]
    search = TeammateSearches(context_of(passable), goals)
    counted.append(search)
    return greedy_auction(bidders, sizes, search, fields)


@settings(max_examples=80, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), mates=st.integers(1, 12))
def test_searching_from_the_goals_never_changes_the_winner(seed: int, mates: int) -> None:
    """The same frontier wins with the goals' searches as with the teammates' own, on
    random maps with teammates that share cells (equal costs: ties broken by rank),
    stand off the passable cells, or cannot reach a goal."""
    if scene(seed, mates) is None:
        return
    searches: list[Any] = []
    assert run_auction(seed, mates, True, searches) == run_auction(seed, mates, False, searches)


def test_a_crowd_behind_the_goal_costs_one_search_not_one_each(
    searched_from: list[tuple[float, float]],
) -> None:
    """Twenty teammates down a corridor, each nearer the frontier than this robot in a
    straight line: the goal's search bounds them all; before, each cost a search of its own."""
    passable = np.zeros((12, 120), dtype=bool)
    passable[5, 1:119] = True
    passable[1:6, 60] = True  # a side corridor: the frontier at its end
    goals = np.array([[1, 60], [5, 118]])
    sizes = np.array([50.0, 1.0])
    me = (20.5, 5.5)
    mine = forward(passable, me, goals)
    mates = [(float(x) + 0.5, 5.5) for x in range(70, 110, 2)]
    won = {}
    for with_fields in (False, True):
        searched_from.clear()
        bidders = [Bidder("me", mine.copy(), np.ones(2, dtype=bool), me, rank=99)]
        bidders += [Bidder.estimated(f"m{i}", xy, goals, i) for i, xy in enumerate(mates)]
        fields = None
        if with_fields:
            fields = GoalFields.for_auction(passable, (1, 6, 1, 119), goals, mates)  # bbox
        search = TeammateSearches(context_of(passable), goals)
        won[with_fields] = (greedy_auction(bidders, sizes, search, fields), len(searched_from))
    assert won[True][0] == won[False][0]
    assert won[False][1] >= 10 and won[True][1] <= 2


def test_teammates_on_one_cell_share_one_search(searched_from: list[tuple[float, float]]) -> None:
    passable = np.ones((20, 20), dtype=bool)
    goals = np.array([[10, 12], [19, 1]])
    calls = searched_from
    search = TeammateSearches(context_of(passable), goals)
    first = search(Bidder.estimated("a", (10.2, 10.7), goals), 0, 30.0)
    again = search(Bidder.estimated("b", (10.9, 10.1), goals), 0, 30.0)
    assert len(calls) == 1 and first is again
    search(Bidder.estimated("c", (10.9, 10.1), goals), 1, 30.0)  # not found by the first
    assert len(calls) == 2
    exact = goal_costs(passable, (10.5, 10.5), goals, 1, np.inf, (0, 20, 0, 20))
    assert exact is not None and search.done[(10, 10)].found[1] == exact.found[1]


def test_a_goal_on_no_passable_cell_is_out_of_every_teammates_reach() -> None:
    """A goal its own search could not start from (a wall cell, or outside the passable
    box) costs every teammate inf, exactly: no teammate's own search would reach it."""
    passable = np.ones((10, 10), dtype=bool)
    passable[5, 5] = False
    cells = np.array([[-1, -1], [1, 1], [8, 8]])
    fields = GoalFields(passable, (0, 10, 0, 10), np.array([[5, 5], [1, 2]]), cells)
    low, high = np.zeros((3, 2)), np.full((3, 2), np.inf)
    known = np.zeros((3, 2), dtype=bool)
    fields.tighten(0, 1, 20.0, low, high, known)
    assert known[:, 0].tolist() == [False, True, True] and np.all(low[1:, 0] == np.inf)
    fields.tighten(1, 1, 20.0, low, high, known)  # a passable goal: bounds, not exact
    assert low[1, 1] <= 1.0 <= high[1, 1] and not known[:, 1].any()


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), pause=st.floats(1.0, 60.0))
def test_a_steered_search_finds_the_teammates_own_float_cost(seed: int, pause: float) -> None:
    """Steered by a goal's search paused anywhere (its final costs and, beyond them, its
    bound), an A* from a teammate finds the very float the teammate's own search finds
    (not one within rounding), or says it cannot tell where the cost is above the limit."""
    made = fields_with_exact_costs(seed, (90, 120))
    if made is None:
        return
    fields, exact = made
    goals, cells = fields.goals_rc, fields.cells
    low, high = np.zeros_like(exact), np.full_like(exact, np.inf)
    known = np.zeros(exact.shape, dtype=bool)
    for goal in range(len(goals)):
        fields.tighten(goal, 0, pause, low, high, known)
        for who in np.flatnonzero(cells[:, 0] >= 0):
            cost = exact[who, goal]
            if np.isfinite(cost) and cost > 2.0:
                assert fields.exact_cost(goal, int(who), cost - 1.0) is None  # not cached
            steered = fields.exact_cost(goal, int(who), cost + 1.0 if np.isfinite(cost) else 90)
            assert steered == (cost if np.isfinite(cost) else None)


def test_tied_teammates_are_told_apart_without_their_own_searches(
    searched_from: list[tuple[float, float]],
) -> None:
    """Two teammates as far from the best frontier as each other: only their exact costs
    (then their ranks) decide, and a search steered by the frontier's finds them, where
    before each teammate searched on its own."""
    passable = np.ones((21, 41), dtype=bool)
    passable[4:17, 20] = False  # a wall between them: their paths run round it
    goals = np.array([[10, 30], [0, 0]])
    sizes = np.array([50.0, 1.0])
    me = (0.5, 20.5)
    mine = forward(passable, me, goals)
    mates = [(10.5, 10.5), (30.5, 3.5), (30.5, 17.5)]
    won = {}
    for with_fields in (False, True):
        searched_from.clear()
        bidders = [Bidder("me", mine.copy(), np.ones(2, dtype=bool), me, rank=9)]
        bidders += [Bidder.estimated(f"m{i}", xy, goals, 2 - i) for i, xy in enumerate(mates)]
        fields = None
        if with_fields:
            fields = GoalFields.for_auction(passable, (0, 21, 0, 41), goals, mates)
        search = TeammateSearches(context_of(passable), goals)
        won[with_fields] = (greedy_auction(bidders, sizes, search, fields), len(searched_from))
        if with_fields:
            assert fields is not None
            tied = [fields.exact_cost(0, who, 20.0) for who in (2, 3)]
            assert tied[0] == tied[1] == forward(passable, mates[1], goals)[0]
    assert won[True][0] == won[False][0]
    assert won[False][1] >= 2 and won[True][1] == 0
