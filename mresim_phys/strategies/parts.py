"""Strategy parts (phase 4, decide): the small policies a frontier strategy is built from.

``frontier`` and every strategy built on it run one loop (``strategies/frontier.py``): find
the robot's frontiers, search for the best reachable ones, pick one with the team in mind,
go there, and return to the base when the mission is complete. What varies between
strategies is a part, never an override of the loop's private steps:

* :class:`FrontierFilter`, which of its frontiers the robot considers: every one
  (:class:`AllFrontiers`), or, for ``leader_follower``'s leader, those the chain reaches;
* :class:`Ranking`, the candidates best first (:meth:`Ranking.candidates`) and whether a
  search out to a horizon has settled them (:meth:`Ranking.settled`): the original's
  utility (:class:`UtilityRanking`), or ``sector_rendezvous``'s wedge first;
* :class:`Allocation`, which candidate of an :class:`Offer` this robot takes given its
  teammates: the greedy auction (:class:`GreedyAuction`), ``hungarian``'s assignment,
  ``min_pos``'s ranks, or ``sector_rendezvous``'s wedge before the auction;
* :class:`DoneRule`, when the mission is complete and the robot goes home though frontiers
  are left: the original's rule (:class:`MissionComplete`).

:class:`FrontierParts` holds one of each; a strategy passes its parts to
``FrontierExploration.__init__``. A new strategy from parts: ``docs/writing-a-strategy.md``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from mresim_phys.knowledge.frontiers import Frontiers
from mresim_phys.knowledge.known_area import free_count
from mresim_phys.knowledge.teammates import TeammateInfo
from mresim_phys.planning.goal_fields import GoalFields
from mresim_phys.strategies.auction import (
    Bidder,
    TeammateSearches,
    greedy_auction,
    teammate_bidders,
)
from mresim_phys.strategies.base import PlanContext, RobotView
from mresim_phys.strategies.frontier_utility import utility
from mresim_phys.types import FloatArray, IntArray

EXPLORES_WITHOUT = frozenset({"drive", "sensor"})  # a teammate with either failed takes no frontier


@runtime_checkable
class FrontierFilter(Protocol):
    """Which of its frontiers a robot considers."""

    def keep(self, view: RobotView, found: Frontiers) -> Frontiers:
        """The frontiers of ``found`` the robot may take (renumbered clusters)."""
        ...


@runtime_checkable
class Ranking(Protocol):
    """The candidates, best first, and when a bounded search has settled them."""

    def candidates(self, frontiers: Frontiers, costs: FloatArray) -> IntArray:
        """Indices of the best reachable frontiers, best first."""
        ...

    def settled(
        self, frontiers: Frontiers, costs: FloatArray, candidates: IntArray, limit: float
    ) -> bool:
        """Whether no frontier beyond the search horizon ``limit`` could change the
        candidates (a frontier there costs at least ``limit``)."""
        ...


@dataclass(frozen=True)
class Offer:
    """What an allocation chooses from: the robot's view and planning context, its
    frontiers, each frontier's target cell and path cost (inf: unreachable), and the
    candidates, best first (indices into ``frontiers``)."""

    view: RobotView
    context: PlanContext
    frontiers: Frontiers
    targets: IntArray
    costs: FloatArray
    candidates: IntArray


@runtime_checkable
class Allocation(Protocol):
    """Which candidate this robot takes, given its teammates."""

    def choose(self, offer: Offer) -> int:
        """The index (into ``offer.frontiers``) of the frontier this robot takes."""
        ...


@runtime_checkable
class DoneRule(Protocol):
    """When the robot goes home although its map still holds frontiers."""

    def met(self, view: RobotView) -> bool:
        """Whether the mission is complete for this robot now."""
        ...


class AllFrontiers:
    """Every frontier of the robot's map."""

    def keep(self, view: RobotView, found: Frontiers) -> Frontiers:
        """``found`` as it is."""
        return found


@dataclass
class UtilityRanking:
    """The best ``max_frontiers`` by ``size / d**power`` compete: the original's utility
    ``size * 1e8 / d**4`` (power 4), its frontier order, area / distance (power 1), or
    between (``FrontierParams.candidate_power``)."""

    max_frontiers: int
    power: int = 4

    def candidates(self, frontiers: Frontiers, costs: FloatArray) -> IntArray:
        """Indices of the best reachable frontiers, best first."""
        u = self.score(frontiers.sizes.astype(float), costs)
        order = np.argsort(-u, kind="stable")
        keep = order[np.isfinite(u[order])]
        return keep[: self.max_frontiers]

    def score(self, sizes: FloatArray, costs: FloatArray) -> FloatArray:
        """What the candidates are ordered by (-inf: unreachable)."""
        return utility(sizes, costs, self.power)

    def settled(
        self, frontiers: Frontiers, costs: FloatArray, candidates: IntArray, limit: float
    ) -> bool:
        """Whether no frontier beyond the search horizon ``limit`` could enter the best
        ``max_frontiers``: the horizon only saves work, the candidates are those of a
        whole-map search."""
        beyond = ~np.isfinite(costs)
        if limit == np.inf or not beyond.any():
            return True
        if len(candidates) < self.max_frontiers:
            return False
        sizes = frontiers.sizes.astype(float)
        best_beyond = self.score(sizes[beyond].max(keepdims=True), np.array([limit]))[0]
        return bool(self.score(sizes[candidates[-1:]], costs[candidates[-1:]])[0] > best_beyond)


def auction_team(view: RobotView, memory: int) -> list[TeammateInfo]:
    """The teammates that take part in an allocation, by name: exploring, heard from within
    ``memory`` steps, not presumed lost, drive and sensor working."""
    return sorted(
        (
            t
            for t in view.teammates.values()
            if t.name != view.name
            and t.role == "explorer"
            and t.state in ("active", "error")
            and view.step - t.step <= memory
            and t.name not in view.lost
            and not EXPLORES_WITHOUT.intersection(t.broken)
        ),
        key=lambda t: t.name,
    )


@dataclass
class GreedyAuction:
    """The original's greedy auction: the best (robot, frontier) pair is fixed, that robot
    and that frontier leave, until the best pair is this robot's (``strategies/auction.py``)."""

    teammate_memory: int

    def choose(self, offer: Offer) -> int:
        """The candidate this robot wins."""
        view, context, candidates = offer.view, offer.context, offer.candidates
        sizes = offer.frontiers.sizes[candidates].astype(float)
        goals = offer.targets[candidates]
        mine = offer.costs[candidates]
        rank = view.tie_rank
        me = Bidder(view.name, mine, np.ones(len(mine), dtype=bool), view.position, rank(view.name))
        team = auction_team(view, self.teammate_memory)
        others = teammate_bidders(
            [t.name for t in team], [t.position for t in team], [rank(t.name) for t in team],
            goals, context.search, mine,
        )  # fmt: skip
        bidders = [me, *others]
        won = greedy_auction(
            bidders,
            sizes,
            TeammateSearches(context, goals),
            goal_fields(context, goals, [t.position for t in team]),
        )
        return int(candidates[won])


def goal_fields(
    context: PlanContext, goals: IntArray, positions: list[tuple[float, float]]
) -> GoalFields | None:
    """Searches from the auction's goals for the teammates at ``positions`` (bidders 1 on),
    on the robot's passable map; None with terrain costs (the teammates' own searches then
    run ``costs.dijkstra_weighted``, which the goal searches do not follow) or no passable
    cell."""
    box = context.passable_box
    if context.slowness is not None or box is None or not positions:
        return None
    return GoalFields.for_auction(context.passable, box, goals, positions)


@dataclass
class MissionComplete:
    """The original's mission-complete rule: after ``after`` steps, the robot's own map
    holds ``fraction`` of the building's free area (known before the mission).

    It sends a robot out of the base's reach home once: when its map has reached the base,
    it explores on until no frontier is left (the original parks it there; a rule that
    fired again on every loss of contact kept robots shuttling between the edge of the
    base's reach and the far frontiers, never reaching them)."""

    fraction: float | None
    after: int
    was_met: bool = False  # the rule sent this robot home
    delivered: bool = False  # ... and its map has reached the base since

    def met(self, view: RobotView) -> bool:
        """Whether the mission is complete for this robot now."""
        if self.fraction is None or view.free_area <= 0 or view.step < self.after:
            return False
        if view.base_contact >= view.step - 1:  # its data reaches the base: nothing to carry
            self.delivered = self.delivered or self.was_met
            return False
        if self.delivered:  # it brought its map home once: it explores on to the end
            return False
        met = free_count(view.belief, view.features) >= self.fraction * view.free_area
        self.was_met = self.was_met or met
        return met


@dataclass
class FrontierParts:
    """The parts of one robot's frontier strategy (module docstring)."""

    filter: FrontierFilter
    ranking: Ranking
    allocation: Allocation
    done: DoneRule
