"""``frontier`` (phase 4, decide): the original's greedy frontier exploration ("return when done").

At every replan the robot finds the frontiers of its own map, scores each as ``U = size *
1e8 / d**4`` (``d`` = path length; original ``FrontierExploration``; ``size``: the
seen-but-unvisited region the frontier borders, as the original's frontier polygons,
``knowledge/frontier_regions.py``) and runs a greedy auction with the teammates it heard
from within ``teammate_memory`` steps and does not presume lost (``RobotView.lost``: a
silent teammate's frontier is auctioned again), nor whose record says its drive or sensor
has failed (it cannot explore a frontier): the best (robot, frontier) pair is fixed, that
robot and that frontier leave the auction, until the best pair is this robot's. So two
robots in contact do not chase the same frontier. A teammate's distance starts as the
straight line from its last known position and is replaced by its exact path length on this
robot's map before its bid can win (as the original does), with a path search bounded to 1.5
times the straight-line estimate, widened only if needed. With nothing reachable left to
explore the robot returns to the base: ``done``.

On arriving, the robot turns to face the frontier (its laser covers only 180
degrees) and scans. A frontier it reached without resolving (unknown cells it cannot
see into from there) is tried again from another spot; its cells within
``give_up_radius`` of two spots tried in vain no longer count as frontier for it, like
the original's "bad frontiers" (``strategies/giveup.py``); the rest of that cluster
stays a frontier. Ties in the auction go by
the team's seeded order (``RobotView.team_order``), so robots that see equal bids
agree on the winner. The first ``init_cycles`` steps are the original's
random-walk steps.
"""

from __future__ import annotations

from dataclasses import replace
from typing import ClassVar

import numpy as np

from mresim_phys.knowledge.frontier_regions import region_sizes
from mresim_phys.knowledge.frontiers import Frontiers, any_frontier, frontiers_in
from mresim_phys.knowledge.prior import PRIOR, walled_in
from mresim_phys.knowledge.targets import TargetFinder, target_reach
from mresim_phys.plugin import Plugin
from mresim_phys.strategies.base import (
    GOAL_MET,
    NO_FRONTIER,
    Decision,
    PlanContext,
    RobotView,
    plan_context,
    return_to_base,
)
from mresim_phys.strategies.catalog import STRATEGIES
from mresim_phys.strategies.giveup import Tried, tried_after_arrival
from mresim_phys.strategies.params import FrontierParams, StrategyParams
from mresim_phys.strategies.parts import (
    AllFrontiers,
    FrontierParts,
    GreedyAuction,
    MissionComplete,
    Offer,
    UtilityRanking,
)
from mresim_phys.strategies.random_walk import random_step
from mresim_phys.types import BeliefGrid, BoolGrid, FloatArray, IntArray


@STRATEGIES.register
class FrontierExploration(Plugin):
    """Greedy utility-based frontier exploration with a teammate auction."""

    name = "frontier"

    Params: ClassVar[type[StrategyParams]] = FrontierParams
    params: FrontierParams

    def __init__(self, params: FrontierParams, parts: FrontierParts | None = None) -> None:
        self.params = params
        self.parts = parts or default_parts(params)
        self._tried: Tried | None = None
        self._chasing: IntArray | None = None
        self._home: tuple[float, float] | None = None

    def decide(self, view: RobotView) -> Decision:
        """Pick the frontier this robot wins in the auction and plan a path to it."""
        context = plan_context(view)
        if view.vary_with_seed and view.step <= self.params.init_cycles:
            step = random_step(view, context)
            if step is not None:
                return step
        tried = self._tried_cells(view)
        frontiers = self._frontiers(view, context, tried.set_aside)
        reach = self.params.reach or target_reach(view.clearance)
        goal_met = len(frontiers) > 0 and self.parts.done.met(view)
        found = self._search(frontiers, context, reach) if not goal_met else None
        if found is None and not goal_met and tried.set_aside_any:
            frontiers = self._frontiers(view, context, tried.given_up)
            found = self._search(frontiers, context, reach, retry=True)
        if found is None:
            self._chasing = None
            reason = GOAL_MET if goal_met else NO_FRONTIER
            decision = return_to_base(view, context, self._home, reason)
            self._home = decision.goal
            return decision
        self._home = None
        targets, costs, candidates = found
        offer = Offer(view, context, frontiers, targets, costs, candidates)
        chosen = self.parts.allocation.choose(offer)
        chasing = self._chasing = frontiers.cells_rc[frontiers.cluster_of == chosen]
        row, col = (int(v) for v in targets[chosen])
        path = context.plan_to(row, col)
        info = {"frontiers": frontiers, "target_cluster": chosen, **context.planner_info()}
        return Decision(
            path=path,
            goal=(col + 0.5, row + 0.5),
            look_at=nearest_cell_centre(chasing, row, col),
            info=info,
        )

    @property
    def given_up(self) -> BoolGrid | None:
        """The frontier cells this robot tried from two spots in vain and gave up
        (``giveup``); None before it tried any. Run health leaves them out."""
        if self._tried is None or not self._tried.gave_up_any:
            return None
        return self._tried.given_up

    def replan_on_contact(self, belief: BeliefGrid) -> bool:
        """Replan after a contact when no cell of the chased frontier is frontier any more.

        The original replans every cycle while a robot receives messages, so a robot
        whose frontier a teammate has explored turns to another one at once. Of those
        replans only the ones whose target is gone are made here (replanning every step
        in contact cost 8 times the run time, library 8 robots). On by default since
        frontiers are weighed by their regions: with both, 12x12_rooms reaches 90 % in
        fewer steps than the original (docs/differences-from-original.md)."""
        chasing = self._chasing
        return bool(
            self.params.replan_on_contact
            and chasing is not None
            and not any_frontier(belief, chasing)
        )

    def _tried_cells(self, view: RobotView) -> Tried:
        """What this robot tried in vain (``giveup``); a frontier it has just reached and
        still holds counts a try."""
        self._tried, self._chasing = tried_after_arrival(
            self._tried, view.belief.shape, view.reached_goal, self._chasing, view.position,
            self.params.give_up_radius,
        )  # fmt: skip
        return self._tried

    def _frontiers(self, view: RobotView, context: PlanContext, tried: BoolGrid) -> Frontiers:
        """This robot's frontier clusters without the ``tried`` cells (nor, with a prior
        map, those behind which the plan shows only walls), as its filter keeps them."""
        exclude = tried
        prior = PRIOR.of(view)
        if prior is not None:  # the plan shows only walls behind these cells
            exclude = exclude | walled_in(view.belief, prior)
        size = self.params.min_frontier_size
        found = frontiers_in(view.belief, context.free_box, size, exclude)
        box = context.free_box
        if self.params.frontier_size == "region" and view.safe is not None and box is not None:
            found = replace(found, sizes=region_sizes(found, view.belief, view.safe, box))
        return self.parts.filter.keep(view, found)

    def _search(
        self, frontiers: Frontiers, context: PlanContext, reach: float, retry: bool = False
    ) -> tuple[IntArray, FloatArray, IntArray] | None:
        """(targets, costs, candidates) of the best reachable frontiers, the search out to
        a growing horizon; None if no frontier is reachable. A ``retry`` (of frontiers set
        aside, ``giveup``) takes no target on a spot tried in vain."""
        if len(frontiers) == 0:
            return None
        cells = context.passable
        if retry and self._tried is not None:
            cells = self._tried.target_cells(cells)
        finder = TargetFinder.of(frontiers, cells, reach)
        for limit, field, final in context.fields_staged(
            self.params.horizon * context.view.sensor_range
        ):
            targets, costs = finder.targets(field, final)
            candidates = self.parts.ranking.candidates(frontiers, costs)
            if len(candidates) and self.parts.ranking.settled(frontiers, costs, candidates, limit):
                return targets, costs, candidates
        return None


def default_parts(params: FrontierParams) -> FrontierParts:
    """The parts of ``frontier``: every frontier, the original's utility, the greedy
    auction, the original's mission-complete rule (``strategies/parts.py``)."""
    return FrontierParts(
        filter=AllFrontiers(),
        ranking=UtilityRanking(params.max_frontiers, params.candidate_power),
        allocation=GreedyAuction(params.teammate_memory),
        done=MissionComplete(params.done_fraction, params.done_after),
    )


def nearest_cell_centre(cells_rc: IntArray, row: int, col: int) -> tuple[float, float]:
    """World centre of the cell of ``cells_rc`` nearest to cell (row, col)."""
    nearest = cells_rc[np.argmin(np.hypot(cells_rc[:, 0] - row, cells_rc[:, 1] - col))]
    return float(nearest[1]) + 0.5, float(nearest[0]) + 0.5
