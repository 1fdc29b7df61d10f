"""Strategies: the plugin registry, the greedy frontier auction, returning when done."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from mresim_phys import STRATEGIES, Simulation, UnknownPluginError
from mresim_phys.agents import Body, TeammateInfo
from mresim_phys.planning.goals import GoalCosts
from mresim_phys.strategies import BUILT_IN, RobotView
from mresim_phys.strategies.auction import Bidder, best_pair, greedy_auction
from mresim_phys.strategies.base import Strategy
from mresim_phys.strategies.frontier import FrontierExploration
from mresim_phys.strategies.params import FrontierParams
from mresim_phys.types import FREE, OCCUPIED, UNKNOWN
from mresim_phys.world.sensing import Laser

MINIMAL = {"policy": {"external": True}}  # a strategy's parameters that have no defaults


def test_registry_holds_the_built_ins() -> None:
    assert set(BUILT_IN) <= set(STRATEGIES.names())
    for name in BUILT_IN:
        cls = STRATEGIES.get(name)
        assert isinstance(cls(cls.Params(**MINIMAL.get(name, {}))), Strategy)


def test_unknown_strategy_lists_close_matches() -> None:
    with pytest.raises(UnknownPluginError, match="'frontier'"):
        STRATEGIES.get("fronteir")


def test_module_reference_resolves_a_user_class() -> None:
    assert STRATEGIES.get("mresim_phys.strategies.random_walk:RandomWalk").name == "random_walk"


def corridor_view(teammates: dict[str, TeammateInfo], position: tuple[float, float]) -> RobotView:
    """A 20x100 known corridor, unknown at both ends: one frontier left, one right."""
    belief = np.full((20, 100), OCCUPIED, dtype=np.uint8)
    belief[5:15, :] = UNKNOWN
    belief[5:15, 20:80] = FREE
    return RobotView(
        step=10,
        name="A",
        position=position,
        heading=0.0,
        belief=belief,
        radius=1.0,
        clearance=2.0,
        speed=2.0,
        sensor_range=30.0,
        role="explorer",
        base_position=(50.5, 10.5),
        teammates=teammates,
        rng=np.random.default_rng(0),
    )


def test_frontier_goes_to_the_nearer_frontier_alone() -> None:
    decision = FrontierExploration(FrontierParams()).decide(corridor_view({}, (45.5, 10.5)))
    assert decision.goal is not None and decision.goal[0] < 50
    assert not decision.done and len(decision.path) > 0


def test_two_robots_in_contact_do_not_chase_the_same_frontier() -> None:
    """A teammate nearer the left frontier wins it; this robot takes the right one."""
    teammate = TeammateInfo("B", (30.5, 10.5), None, "active", "explorer", step=9)
    decision = FrontierExploration(FrontierParams()).decide(
        corridor_view({"B": teammate}, (45.5, 10.5))
    )
    assert decision.goal is not None and decision.goal[0] > 50


def test_stale_or_failed_teammates_take_no_part() -> None:
    params = FrontierParams(teammate_memory=5)
    stale = TeammateInfo("B", (30.5, 10.5), None, "active", "explorer", step=1)
    failed = TeammateInfo("C", (30.5, 10.5), None, "failed", "explorer", step=9)
    for mate in (stale, failed):
        decision = FrontierExploration(params).decide(
            corridor_view({mate.name: mate}, (45.5, 10.5))
        )
        assert decision.goal is not None and decision.goal[0] < 50


def test_nothing_left_to_explore_means_done_and_home() -> None:
    view = corridor_view({}, (45.5, 10.5))
    belief = view.belief.copy()
    belief[belief == UNKNOWN] = OCCUPIED
    closed = RobotView(**{**view.__dict__, "belief": belief, "position": (70.5, 10.5)})
    decision = FrontierExploration(FrontierParams()).decide(closed)
    assert decision.done
    assert decision.path[-1] == pytest.approx([50.5, 10.5])


def test_auction_refines_estimates_before_a_teammate_wins() -> None:
    """A teammate that looks close in a straight line but is far by path does not win."""
    sizes = np.array([10.0, 10.0])
    me = Bidder("A", np.array([10.0, 30.0]), np.ones(2, dtype=bool), (0.0, 0.0))
    mate = Bidder("B", np.array([5.0, 50.0]), np.zeros(2, dtype=bool), (0.0, 0.0))
    searched: list[float] = []

    def search(bidder: Bidder, wanted: int, limit: float) -> GoalCosts:
        searched.append(limit)
        return GoalCosts(np.where(np.array([100.0, 100.0]) <= limit, 100.0, np.inf), limit)

    assert greedy_auction([me, mate], sizes, search) == 0
    assert mate.costs[0] > 10.0  # its bound rose past both estimates: no longer a threat
    assert searched and searched[0] < 100.0  # the first search was bounded


def reference_best_pair(
    u: np.ndarray, ranks: np.ndarray, active: np.ndarray, taken: np.ndarray
) -> tuple[int, int]:
    """The numpy rule ``best_pair`` compiles: row argmax, then the best bid, lowest rank."""
    open_ = np.where(active[:, None] & ~taken[None, :], u, -np.inf)
    which = np.argmax(open_, axis=1)
    bids = open_[np.arange(len(u)), which]
    if not (bids > -np.inf).any():
        return -1, -1
    best = bids == bids.max()
    who = int(np.flatnonzero(best & (ranks == ranks[best].min()))[0])
    return who, int(which[who])


@pytest.mark.parametrize("seed", range(200))
def test_best_pair_follows_the_numpy_rule(seed: int) -> None:
    rng = np.random.default_rng(seed)
    bidders, frontiers = int(rng.integers(1, 9)), int(rng.integers(1, 7))
    u = rng.choice([-np.inf, 0.0, 1.0, 2.0, 3.5], size=(bidders, frontiers))  # many ties
    ranks = rng.integers(0, 4, bidders)
    active, taken = rng.random(bidders) < 0.8, rng.random(frontiers) < 0.3
    assert best_pair(u, ranks, active, taken) == reference_best_pair(u, ranks, active, taken)


def test_auction_lets_a_teammate_nearer_by_path_win() -> None:
    sizes = np.array([10.0, 10.0])
    me = Bidder("A", np.array([10.0, 30.0]), np.ones(2, dtype=bool), (0.0, 0.0))
    mate = Bidder("B", np.array([4.0, 50.0]), np.zeros(2, dtype=bool), (0.0, 0.0))
    won = greedy_auction(
        [me, mate], sizes, lambda b, k, limit: GoalCosts(np.array([5.0, 60.0]), limit)
    )
    assert won == 1 and mate.exact.all()


def test_robots_that_outnumber_the_frontiers_bid_again_over_all_of_them() -> None:
    """The original's keepAssigningRobotsToFrontiers: once every frontier is taken, the
    robots not yet assigned bid again over all of them, so they spread instead of all
    following their own best."""
    sizes = np.array([10.0, 10.0])
    exact = np.ones(2, dtype=bool)
    me = Bidder("A", np.array([10.0, 20.0]), exact, (0.0, 0.0), rank=3)
    first = Bidder("B", np.array([1.0, 100.0]), exact.copy(), (0.0, 0.0), rank=0)
    second = Bidder("C", np.array([100.0, 1.0]), exact.copy(), (0.0, 0.0), rank=1)
    again = Bidder("D", np.array([5.0, 30.0]), exact.copy(), (0.0, 0.0), rank=2)
    won = greedy_auction([me, first, second, again], sizes, lambda b, limit: None)
    assert won == 1  # D wins frontier 0 in the second round; A's own best was 0


def test_frontiers_beyond_the_first_horizon_still_enter_the_auction() -> None:
    """The search horizon only saves work: a robot with one frontier near and one far,
    whose teammate is nearer the near one, takes the far one."""
    teammate = TeammateInfo("B", (22.5, 10.5), None, "active", "explorer", step=9)
    view = corridor_view({"B": teammate}, (28.5, 10.5))  # right frontier ~47 > range 30
    decision = FrontierExploration(FrontierParams()).decide(view)
    assert decision.goal is not None and decision.goal[0] > 50


def test_robots_finish_and_return_to_base(scenario_file: Callable[..., Path]) -> None:
    sim = Simulation.from_yaml(scenario_file(steps=400, stop={"all_done": True}))
    sim.run()
    assert sim.stop_reason() == "all_done"
    assert all(r.state == "done" for r in sim.robots)
    base = np.array(sim.base.position)
    assert all(np.hypot(*(np.array(r.position) - base)) < 6 for r in sim.robots)
    assert sim.record.explored > 0.9


def test_random_walk_stays_within_its_leg_length(scenario_file: Callable[..., Path]) -> None:
    sim = Simulation.from_yaml(
        scenario_file(
            team={
                "speed": 2,
                "radius": 1.0,
                "sensor": {"range": 30},
                "comm_range": 20,
                "strategy": {"name": "random_walk", "params": {"distance": 10}},
            }
        )
    )
    for _ in range(20):
        sim.step()
        for robot in sim.robots:
            assert robot.goal is None or len(robot.decision.path) <= 12


def test_robots_on_one_spot_agree_on_who_takes_which_frontier() -> None:
    """Equal bids go by the team's order, so two robots with the same view split up."""
    goals = {}
    for me, other in (("A", "B"), ("B", "A")):
        mate = TeammateInfo(other, (50.0, 10.5), None, "active", "explorer", step=9)
        view = corridor_view({other: mate}, (50.0, 10.5))
        view = RobotView(**{**view.__dict__, "name": me, "team_order": ("B", "A")})
        decision = FrontierExploration(FrontierParams()).decide(view)
        assert decision.goal is not None
        goals[me] = decision.goal[0] < 50
    assert goals["A"] != goals["B"]


def test_an_unresolved_frontier_is_tried_from_another_spot_then_given_up_near_it() -> None:
    """A long frontier: one try from a spot sets the cells near it aside (chased again,
    from elsewhere, when nothing else is left); a second try gives up the cells near both
    spots, the far ones stay."""
    from mresim_phys.knowledge.frontiers import find_frontiers
    from mresim_phys.strategies.giveup import Tried

    belief = np.full((20, 100), FREE, dtype=np.uint8)
    belief[:2, :] = UNKNOWN  # a 100-cell frontier along the top (row 2)
    frontiers = find_frontiers(belief)
    assert len(frontiers) == 1
    tried = Tried.empty(belief.shape)
    tried.failed(frontiers.cells_rc, (5.5, 3.5), radius=10.0)
    assert not tried.given_up.any() and not tried.gave_up_any and tried.set_aside_any
    assert tried.spots[3, 5] and not tried.spots[3, 8]
    assert tried.set_aside[2, :15].all() and not tried.set_aside[2, 15:].any()
    spared = tried.target_cells(np.ones(belief.shape, dtype=bool))
    assert not spared[3, 5] and spared[3, 8]
    tried.failed(frontiers.cells_rc, (8.5, 3.5), radius=10.0)
    assert tried.given_up[2, :15].all() and not tried.given_up[2, 15:].any()
    assert tried.gave_up_any  # read every step instead of scanning the grid
    left = find_frontiers(belief, exclude=tried.given_up)
    assert len(left) == 1 and left.cells_rc[:, 1].min() == 15


def test_a_robot_whose_map_holds_the_goal_fraction_goes_home() -> None:
    """The original's mission-complete rule: own map >= 95 % of the free area, after step 100."""
    view = corridor_view({}, (45.5, 10.5))
    free = int(np.count_nonzero(view.belief == FREE))
    strategy = FrontierExploration(FrontierParams())
    for step, area, done in ((150, free, True), (50, free, False), (150, 2 * free, False)):
        later = RobotView(**{**view.__dict__, "step": step, "free_area": area})
        assert strategy.decide(later).done is done


def test_the_first_steps_are_seeded_random_walk_steps() -> None:
    view = corridor_view({}, (45.5, 10.5))
    steps = []
    for seed in range(8):
        early = RobotView(**{**view.__dict__, "step": 1, "rng": np.random.default_rng(seed)})
        decision = FrontierExploration(FrontierParams()).decide(early)
        (x0, y0), (x1, y1) = decision.path
        assert (x0, y0) == early.position
        assert np.hypot(x1 - x0, y1 - y0) <= early.speed + 1e-9
        assert view.belief[int(y1), int(x1)] == FREE
        steps.append((round(x1, 6), round(y1, 6)))
    assert len(set(steps)) > 1
    fixed = RobotView(**{**view.__dict__, "step": 1, "vary_with_seed": False})
    assert "frontiers" in FrontierExploration(FrontierParams()).decide(fixed).info


def test_a_random_step_never_leaves_known_free_space() -> None:
    from mresim_phys.strategies.base import plan_context
    from mresim_phys.strategies.random_walk import random_step

    view = corridor_view({}, (45.5, 10.5))
    boxed = view.belief.copy()
    boxed[:, 44] = boxed[:, 47] = OCCUPIED  # a slot 2 cells wide: nowhere to step
    cornered = RobotView(**{**view.__dict__, "belief": boxed})
    assert random_step(cornered, plan_context(cornered)) is None


@pytest.mark.parametrize("enabled", [True, False])
def test_a_robot_in_contact_replans_once_its_frontier_is_gone(enabled: bool) -> None:
    """replan_on_contact: the chased frontier left the map (a teammate explored it)."""
    from mresim_phys.agents import Robot
    from mresim_phys.motion import wants_plan

    view = corridor_view({}, (45.5, 10.5))
    strategy = FrontierExploration(FrontierParams(replan_on_contact=enabled))
    strategy.decide(view)
    belief = view.belief.copy()
    assert not strategy.replan_on_contact(belief)  # its frontier is still there
    belief[5:15, :20] = FREE  # the left end explored by a teammate
    belief[5:15, 80:] = FREE  # and the right one
    assert strategy.replan_on_contact(belief) is enabled
    body = Body(1.0, 1.0, 0.5, Laser(10.0))
    robot = Robot(
        "A", 1, view.position, 10.0, belief, np.zeros_like(belief, bool), "explorer", body=body
    )
    robot.strategy, robot.last_plan_step = strategy, view.step
    assert not wants_plan(robot, view.step + 1, 15)  # no contact, no replan
    robot.links = ("B",)
    assert wants_plan(robot, view.step + 1, 15) is enabled


def unvisited_view(safe_right: bool) -> RobotView:
    """The corridor, seen whole from the middle: its right half seen only from afar (not
    safe) unless ``safe_right``. The robot stands nearer the left frontier."""
    view = corridor_view({}, (45.5, 10.5))
    safe = np.zeros(view.belief.shape, dtype=bool)
    safe[5:15, 20:58] = True  # scanned from near by: the left half
    if safe_right:
        safe[5:15, 58:80] = True
    return RobotView(**{**view.__dict__, "safe": safe})


@pytest.mark.parametrize("size", ["region", "cells"])
def test_a_frontier_before_unvisited_space_outweighs_a_nearer_one(size: str) -> None:
    """The original weighs a frontier by the seen-but-unvisited region behind it: the right
    end (22 columns seen only from afar) beats the nearer left end (no such region)."""
    params = FrontierParams(frontier_size=size, init_cycles=0)
    decision = FrontierExploration(params).decide(unvisited_view(safe_right=False))
    assert decision.goal is not None
    assert (decision.goal[0] > 50) is (size == "region")  # by its own cells: the nearer
    both_safe = FrontierExploration(params).decide(unvisited_view(safe_right=True))
    assert both_safe.goal is not None and both_safe.goal[0] < 50  # nothing behind either
