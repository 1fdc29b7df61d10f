"""``hungarian`` and ``min_pos`` (phase 4, decide): frontier exploration with a team assignment.

Both explore as ``frontier`` does (the robot's own frontiers and their targets, the
original's utility to pick the candidates, the initial random steps, giving up
unresolved frontier cells, going home when nothing is left), but replace its greedy
auction by a rule over the whole team's path costs. Teammates are the ones it heard
from within ``teammate_memory`` steps, active, exploring and not presumed lost
(``RobotView.lost``: silent for longer than ``simulation.presume_lost_after``), so a
failed robot's frontier is taken up by the others once its silence is long enough.
A teammate's path costs are searched on this robot's map from the teammate's last
reported position (:func:`teammate_costs`).

* ``hungarian`` (an optimal assignment, as forks of the original added): the cost
  matrix of every robot (rows in the team's tie-break order) to every candidate
  frontier is solved with ``scipy.optimize.linear_sum_assignment`` (least total path
  cost; unreachable pairs cost :data:`UNREACHABLE`). A robot left without a frontier
  (more robots than candidates) takes its own best one.
* ``min_pos`` (Bautin, Simonin and Charpillet, "MinPos: a novel frontier allocation
  algorithm for multi-robot exploration", ICIRA 2012): for each candidate frontier the
  robot's *rank* is the number of teammates nearer to it by path (an equal cost counts
  when the teammate comes first in the team's order); it takes the frontier where its
  rank is lowest, the nearer of equal ranks. Robots so spread over the frontiers in
  the directions where they are ahead of the others.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import ClassVar

import numpy as np
from scipy.optimize import linear_sum_assignment

from mresim_phys.knowledge.teammates import TeammateInfo
from mresim_phys.strategies.base import PlanContext, RobotView
from mresim_phys.strategies.catalog import STRATEGIES
from mresim_phys.strategies.frontier import FrontierExploration, default_parts
from mresim_phys.strategies.params import (
    HungarianParams,
    MinPosParams,
    StrategyParams,
)
from mresim_phys.strategies.parts import Offer, auction_team
from mresim_phys.types import FloatArray, IntArray

UNREACHABLE = 1e9  # cost of an unreachable (robot, frontier) pair in the assignment


def teammate_costs(
    context: PlanContext, position: tuple[float, float], goals_rc: IntArray, limit: float
) -> FloatArray:
    """Path costs on this robot's map from a teammate's ``position`` to the goal cells,
    searched up to ``limit`` (farther or unreachable: inf)."""
    field = context.field_from(position, limit)
    if field.start_rc is None:
        return np.full(len(goals_rc), np.inf)
    costs: FloatArray = field.cost_at(goals_rc[:, 0], goals_rc[:, 1])
    return costs


def assign(costs: FloatArray) -> IntArray:
    """The column each row gets in a least-total-cost assignment of rows to columns
    (-1: none, when there are more rows than columns); inf costs :data:`UNREACHABLE`."""
    matrix = np.where(np.isfinite(costs), costs, UNREACHABLE)
    rows, cols = linear_sum_assignment(matrix)
    out = np.full(len(costs), -1, dtype=np.intp)
    out[rows] = cols
    return out


def min_pos_choice(mine: FloatArray, others: FloatArray, ahead: IntArray) -> int:
    """The index of the frontier where this robot ranks best: ``mine`` its costs, ``others``
    (teammates x frontiers) theirs, ``ahead`` (teammates,) 1 for a teammate that wins a tie
    (it comes first in the team's order). Ties of rank go to the cheaper frontier, then the
    first; unreachable frontiers (inf ``mine``) are never chosen (-1 if all are)."""
    if not np.isfinite(mine).any():
        return -1
    nearer = (others < mine[None, :]) | ((others == mine[None, :]) & (ahead[:, None] > 0))
    rank = nearer.sum(axis=0).astype(float)
    rank[~np.isfinite(mine)] = np.inf
    order = np.lexsort((np.arange(len(mine)), mine, rank))
    return int(order[0])


def assignment_team(view: RobotView, memory: int) -> list[TeammateInfo]:
    """The teammates that take part (as in the auction), in the team's tie-break order."""
    return sorted(auction_team(view, memory), key=lambda t: (view.tie_rank(t.name), t.name))


def team_costs(
    context: PlanContext, team: list[TeammateInfo], goals: IntArray, limit: float
) -> FloatArray:
    """(teammates x goals) path costs on this robot's map, each searched up to ``limit``."""
    rows = [teammate_costs(context, t.position, goals, limit) for t in team]
    return np.array(rows).reshape(len(team), len(goals))


def farthest(costs: FloatArray) -> float:
    """The largest finite cost (0 if none)."""
    finite = costs[np.isfinite(costs)]
    return float(finite.max()) if len(finite) else 0.0


@dataclass
class HungarianAssignment:
    """The allocation of ``hungarian``: the team's least-total-cost assignment."""

    teammate_memory: int

    def choose(self, offer: Offer) -> int:
        """Solve the team's assignment; take the column of this robot's row. A teammate
        is searched to twice this robot's farthest candidate plus a sensor range; beyond
        that it counts as that far (a lower bound of its cost)."""
        view, context, candidates = offer.view, offer.context, offer.candidates
        goals, mine = offer.targets[candidates], offer.costs[candidates]
        team = assignment_team(view, self.teammate_memory)
        limit = 2.0 * farthest(mine) + view.sensor_range
        others = np.minimum(team_costs(context, team, goals, limit), limit)
        me = view.tie_rank(view.name)
        row = sum(1 for t in team if view.tie_rank(t.name) < me)
        column = int(assign(np.insert(others, row, mine, axis=0))[row])
        return int(candidates[column if column >= 0 else 0])


@dataclass
class MinPosAllocation:
    """The allocation of ``min_pos``: the frontier where the fewest teammates are nearer."""

    teammate_memory: int

    def choose(self, offer: Offer) -> int:
        """Rank this robot on each candidate; a teammate is searched only as far as this
        robot's farthest candidate (beyond it, it is nearer to none)."""
        view, context, candidates = offer.view, offer.context, offer.candidates
        goals, mine = offer.targets[candidates], offer.costs[candidates]
        team = assignment_team(view, self.teammate_memory)
        others = team_costs(context, team, goals, farthest(mine))
        me = view.tie_rank(view.name)
        ahead = np.array([int(view.tie_rank(t.name) < me) for t in team], dtype=np.intp)
        return int(candidates[max(min_pos_choice(mine, others, ahead), 0)])


@STRATEGIES.register
class HungarianExploration(FrontierExploration):
    """Optimal robot-to-frontier assignment over path costs at every replan."""

    name = "hungarian"
    Params: ClassVar[type[StrategyParams]] = HungarianParams

    def __init__(self, params: HungarianParams) -> None:
        parts = default_parts(params)
        super().__init__(
            params, replace(parts, allocation=HungarianAssignment(params.teammate_memory))
        )


@STRATEGIES.register
class MinPosExploration(FrontierExploration):
    """MinPos: the frontier where the fewest teammates are nearer than this robot."""

    name = "min_pos"
    Params: ClassVar[type[StrategyParams]] = MinPosParams

    def __init__(self, params: MinPosParams) -> None:
        parts = default_parts(params)
        super().__init__(
            params, replace(parts, allocation=MinPosAllocation(params.teammate_memory))
        )
