"""Phase 4b: a robot's own search paused at cost bounds gives the whole field's answers.

The frontier strategy searches only as far as its best frontiers need (``planning.dial``,
``PlanContext.fields_staged``); these tests hold it to the contract that makes that safe:
the costs below each pause are the whole field's, resuming ends in the very arrays of one
unpaused search, and the frontier targets read from a paused field are the whole field's
for every cluster it has settled.
"""

from __future__ import annotations

import threading

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from test_frontiers import random_belief

from mresim_phys.knowledge.frontiers import find_frontiers
from mresim_phys.knowledge.targets import TargetFinder, frontier_targets
from mresim_phys.planning.dial import PausedSearch, _dijkstra
from mresim_phys.planning.fields import distance_field, traversable
from mresim_phys.planning.grid import Window, bbox
from mresim_phys.strategies.base import RobotView, plan_context
from mresim_phys.strategies.frontier import FrontierExploration
from mresim_phys.strategies.params import FrontierParams
from mresim_phys.types import FREE, OCCUPIED, UNKNOWN

SEEDS = st.integers(0, 2**32 - 1)
BOUNDS = st.lists(st.floats(0.0, 80.0), min_size=1, max_size=6)


def start_cell(passable: np.ndarray, seed: int) -> tuple[int, int] | None:
    rows, cols = np.nonzero(passable)
    if len(rows) == 0:
        return None
    i = int(np.random.default_rng(seed).integers(len(rows)))
    return int(rows[i]), int(cols[i])


@settings(max_examples=60, deadline=None)
@given(seed=SEEDS, bounds=BOUNDS)
def test_costs_below_each_pause_are_final_and_resuming_gives_the_whole_search(
    seed: int, bounds: list[float]
) -> None:
    passable = traversable(random_belief(seed, (40, 50)), 0.8)
    start = start_cell(passable, seed)
    box = bbox(passable)
    if start is None or box is None:
        return
    window = Window.around(passable, box)
    whole, whole_pred, _ = _dijkstra(window.pad, window.wp, window.node(start), np.inf)
    search = PausedSearch(passable, start, box)
    for bound in bounds:
        search.run_below(bound)
        final = search.final_below
        assert final >= bound or search.finished
        below = whole < final
        np.testing.assert_array_equal(search.dist[below], whole[below])
        assert (search.dist[~below] >= final).all()  # the rest: provisional or unreached
    search.run_below(np.inf)
    assert search.finished and search.final_below == np.inf
    np.testing.assert_array_equal(search.dist, whole)
    np.testing.assert_array_equal(search.pred, whole_pred)


@settings(max_examples=60, deadline=None)
@given(seed=SEEDS, bound=st.floats(1.0, 60.0), reach=st.sampled_from([1.0, 2.5, 4.0]))
def test_targets_from_a_paused_field_are_the_whole_fields_below_the_pause(
    seed: int, bound: float, reach: float
) -> None:
    belief = random_belief(seed, (36, 44))
    passable = traversable(belief, 0.8)
    start = start_cell(passable, seed)
    if start is None:
        return
    frontiers = find_frontiers(belief, min_size=1)
    whole = distance_field(passable, (start[1] + 0.5, start[0] + 0.5))
    expected_targets, expected_costs = frontier_targets(frontiers, whole, passable, reach)
    view = belief_view(belief, (start[1] + 0.5, start[0] + 0.5), clearance=0.8)
    context = plan_context(view)
    finder = TargetFinder.of(frontiers, context.passable, reach)
    for limit, field, final in context.fields_staged(bound):
        targets, costs = finder.targets(field, final)
        settled = expected_costs < final
        np.testing.assert_array_equal(costs[settled], expected_costs[settled])
        np.testing.assert_array_equal(targets[settled], expected_targets[settled])
        assert np.isinf(costs[~settled]).all()
        assert (expected_costs[~settled] >= limit).all()
    np.testing.assert_array_equal(context.field.window_costs, whole.window_costs)


def belief_view(belief: np.ndarray, position: tuple[float, float], clearance: float) -> RobotView:
    return RobotView(
        step=10, name="A", position=position, heading=0.0, belief=belief, radius=0.3,
        clearance=clearance, speed=2.0, sensor_range=30.0, role="explorer",
        base_position=position, teammates={}, rng=np.random.default_rng(0),
    )  # fmt: skip


def test_a_near_frontier_is_chosen_without_searching_the_far_rooms() -> None:
    """A corridor of 400 cells: the robot at its west end, a frontier next to it and one at
    the far end. The paused search settles the near one (utility falls as cost^4) and stops
    long before the far end; the decision is the one a whole-map search gives."""
    belief = np.full((9, 420), OCCUPIED, dtype=np.uint8)
    belief[2:7, 2:418] = FREE
    belief[2:7, 418] = UNKNOWN  # far frontier
    belief[0:2, 10:16] = UNKNOWN  # near frontier through a gap in the north wall
    belief[2, 10:16] = FREE
    view = belief_view(belief, (4.5, 4.5), clearance=1.0)
    strategy = FrontierExploration(FrontierParams(horizon=0.5))  # first pause at 15 cells
    decision = strategy.decide(view)
    assert decision.goal is not None and decision.goal[0] < 30
    context = plan_context(view)
    paused = context.search
    assert paused is not None
    for _ in context.fields_staged(15.0):
        break  # what decide did: one pause
    assert not paused.finished and paused.final_below == 15.0
    assert np.count_nonzero(np.isfinite(paused.dist)) < 0.1 * np.count_nonzero(belief == FREE)
    whole = FrontierExploration(FrontierParams(horizon=100.0)).decide(view)  # one bound: all
    assert whole.goal == decision.goal
    np.testing.assert_array_equal(whole.path, decision.path)


def test_terrain_costs_fall_back_to_growing_bounded_fields() -> None:
    belief = np.full((20, 20), FREE, dtype=np.uint8)
    belief[:, 15:] = UNKNOWN
    view = belief_view(belief, (2.5, 2.5), clearance=0.8)
    mud = np.ones((20, 20))
    mud[5:9, :] = 0.5  # a band of slow ground across the room
    context = plan_context(RobotView(**{**view.__dict__, "features": {"terrain": mud}}))
    assert context.slowness is not None and context.search is None
    stages = list(context.fields_staged(4.0))
    assert stages[-1][0] == np.inf and all(final == np.inf for _, _, final in stages)
    limits = [limit for limit, _, _ in stages]
    assert limits[:2] == [4.0, 8.0]  # bounded fields of doubling horizons
    assert np.isfinite(stages[0][1].window_costs).sum() < np.isfinite(stages[-1][1].costs).sum()


def test_a_robot_with_no_passable_cell_near_it_has_no_search() -> None:
    belief = np.full((10, 10), UNKNOWN, dtype=np.uint8)
    belief[7:, 7:] = FREE
    context = plan_context(belief_view(belief, (1.5, 1.5), clearance=0.5))
    assert context.search is None
    assert context.field.start_rc is None


def test_the_planner_takes_the_window_the_robots_search_built() -> None:
    """A replan builds the window over its passable mask for its own search; the planner's
    ``Window.of`` of that same array (same thread) takes it instead of copying the mask
    again, and it is the window ``Window.of`` would build. Another array, even one equal
    to it, and another thread build their own."""
    belief = np.full((30, 40), OCCUPIED, dtype=np.uint8)
    belief[3:27, 3:37] = FREE
    belief[10:20, 30:37] = UNKNOWN
    context = plan_context(belief_view(belief, (5.5, 5.5), clearance=1.0))
    search = context.search
    assert search is not None
    passable = context.passable
    assert Window.of(passable) is search.window
    built = Window.of(passable.copy())
    assert built is not None and built is not search.window
    assert built.wp == search.window.wp and built.origin == search.window.origin
    np.testing.assert_array_equal(built.pad, search.window.pad)
    elsewhere: list[Window | None] = []
    thread = threading.Thread(target=lambda: elsewhere.append(Window.of(passable)))
    thread.start()
    thread.join()
    assert elsewhere[0] is not None and elsewhere[0] is not search.window
    np.testing.assert_array_equal(elsewhere[0].pad, search.window.pad)
