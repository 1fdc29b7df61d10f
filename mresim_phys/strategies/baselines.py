"""Baselines (phase 4, decide): the exploration strategies papers compare against.

Both explore as ``frontier`` does (the robot's own frontier clusters, their target cells and
path costs, giving up unresolved frontier cells, going home when nothing is left, the
initial random steps) with other parts (``strategies/parts.py``):

* ``nearest_frontier``: uncoordinated nearest-frontier exploration (B. Yamauchi,
  "Frontier-based exploration using multiple robots", Agents 1998): every robot goes to the
  frontier nearest to it by path, whatever its teammates do. No auction, no utility, no
  mission-complete rule: it returns to the base when no frontier is left.
* ``voronoi``: Voronoi partitioning of the frontiers: a frontier cell belongs to the robot
  nearest to it (straight-line distance from the last known positions; ties to the first
  in the team's order), among this robot and the teammates it heard from within
  ``teammate_memory`` steps, not presumed lost and whose drive and sensor work; a robot
  takes the nearest frontier of its own cell by path, and never one in a living
  teammate's cell. A robot whose cell holds no frontier returns to the base; as it moves
  its cell moves with it, and the cell of a teammate that failed (or is presumed lost)
  becomes its neighbours'. (The partition of K. M. Wurm, C. Stachniss, W. Burgard,
  "Coordinated multi-robot exploration using a segmentation of the environment", IROS
  2008, and of J. Hu et al., "Voronoi-based multi-robot autonomous exploration in unknown
  environments via deep reinforcement learning", IEEE T-VT 2020, by distance to robots.)

And the original MRESim's two frontier variants its paper names (``frontiertype``
RangeConstrained and PeriodicReturn, not implemented in its released code; a fork's
PeriodicReturn returns every 100 cycles), on ``frontier``'s greedy auction:

* ``range_constrained``: only frontiers within ``range`` (default: twice the robot's radio
  range, the disk model's reach to a base of the same range) of the base station, so the
  team stays within reach of it; with none left the robot goes home, done;
* ``periodic_return``: a robot ``period`` steps (100) out of contact with the base goes
  back until it is in contact again, then explores on.

And a potential-field explorer after MMPF (J. Yu, J. Tong, Y. Xu, Z. Xu, H. Dong, T. Yang,
Y. Wang, "SMMR-Explore: SubMap-based multi-robot exploration system with multi-robot
multi-target potential field exploration method", ICRA 2021):

* ``potential_field``: every frontier attracts the robot by its size over its path cost
  (the attractive potential of many targets), every teammate it heard from and does not
  presume lost repels it from the frontiers near that teammate (a linear repulsive
  potential, ``repulsion`` cells wide (default a quarter of its laser range), weighted
  ``repulsion_weight``); the robot takes the
  frontier where attraction minus repulsion is highest. The field is evaluated at the
  frontiers' target cells, not descended cell by cell as MMPF's robots do.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import ClassVar

import numpy as np

from mresim_phys.knowledge.frontiers import Frontiers
from mresim_phys.strategies.base import Decision, RobotView, heading_for, plan_context
from mresim_phys.strategies.catalog import STRATEGIES
from mresim_phys.strategies.frontier import FrontierExploration, default_parts
from mresim_phys.strategies.params import (
    NearestFrontierParams,
    PeriodicReturnParams,
    PotentialFieldParams,
    RangeConstrainedParams,
    StrategyParams,
    VoronoiParams,
)
from mresim_phys.strategies.parts import (
    AllFrontiers,
    FrontierFilter,
    FrontierParts,
    Offer,
    auction_team,
)
from mresim_phys.types import FloatArray, IntArray


@dataclass
class NearestRanking:
    """Every reachable frontier, nearest (by path) first; settled once the nearest found
    lies within the search horizon (a frontier beyond it costs more)."""

    def candidates(self, frontiers: Frontiers, costs: FloatArray) -> IntArray:
        """Indices of the reachable frontiers, nearest first (ties: the first cluster)."""
        order = np.argsort(costs, kind="stable")
        kept: IntArray = order[np.isfinite(costs[order])]
        return kept

    def settled(
        self, frontiers: Frontiers, costs: FloatArray, candidates: IntArray, limit: float
    ) -> bool:
        """Whether the nearest found cannot be beaten beyond the horizon ``limit``."""
        return limit == np.inf or (len(candidates) > 0 and bool(costs[candidates[0]] <= limit))


class OwnChoice:
    """The robot takes its own first candidate, whatever its teammates do."""

    def choose(self, offer: Offer) -> int:
        """The first candidate."""
        return int(offer.candidates[0])


class NeverDone:
    """No mission-complete rule: a robot explores until no frontier is left."""

    def met(self, view: RobotView) -> bool:
        """Never."""
        return False


@dataclass
class VoronoiCell:
    """The frontier cells nearer to this robot than to any living teammate it knows of."""

    teammate_memory: int

    def keep(self, view: RobotView, found: Frontiers) -> Frontiers:
        """``found`` with only the cells of this robot's Voronoi cell (module docstring)."""
        team = auction_team(view, self.teammate_memory)
        if not team or len(found) == 0:
            return found
        cells = found.cells_rc.astype(float) + 0.5  # (row, col) centres

        def gap(p: tuple[float, float]) -> FloatArray:
            return np.hypot(cells[:, 1] - p[0], cells[:, 0] - p[1])

        mine = gap(view.position)
        rank = view.tie_rank(view.name)
        keep = np.ones(len(cells), dtype=bool)
        for mate in team:
            theirs = gap(mate.position)
            before = view.tie_rank(mate.name) < rank
            keep &= (mine < theirs) | ((mine == theirs) & (not before))
        return keep_cells(found, keep)


def keep_cells(found: Frontiers, kept: np.ndarray) -> Frontiers:
    """``found`` with only the ``kept`` cells; clusters left without a cell dropped and the
    others renumbered, their sizes and centroids those of their kept cells."""
    clusters = found.cluster_of[kept]
    counts = np.bincount(clusters, minlength=len(found))
    alive = counts > 0
    new_index = np.cumsum(alive) - 1
    cells = found.cells_rc[kept]
    sums = np.column_stack(
        (
            np.bincount(clusters, weights=cells[:, 1], minlength=len(found)),
            np.bincount(clusters, weights=cells[:, 0], minlength=len(found)),
        )
    )
    centroids = sums[alive] / counts[alive, None] + 0.5
    return Frontiers(
        sizes=counts[alive].astype(np.intp),
        centroids=centroids,
        cells_rc=cells,
        cluster_of=new_index[clusters].astype(np.intp),
    )


def nearest_parts(cell: FrontierFilter | None = None) -> FrontierParts:
    """Nearest frontier first, taken whatever the teammates do, no mission-complete rule
    (``cell``: which frontiers count; default every one)."""
    return FrontierParts(
        filter=cell or AllFrontiers(), ranking=NearestRanking(), allocation=OwnChoice(),
        done=NeverDone(),
    )  # fmt: skip


@dataclass
class NearBase:
    """The frontier cells within ``range`` of the base station (None: twice the robot's
    radio range, the disk model's reach to a base of the same range)."""

    range: float | None

    def keep(self, view: RobotView, found: Frontiers) -> Frontiers:
        """``found`` with only the cells within reach of the base."""
        if len(found) == 0:
            return found
        reach = 2 * view.comm_range if self.range is None else self.range
        x, y = view.base_position
        cells = found.cells_rc
        near = np.hypot(cells[:, 1] + 0.5 - x, cells[:, 0] + 0.5 - y) <= reach
        return keep_cells(found, near)


@STRATEGIES.register
class RangeConstrained(FrontierExploration):
    """Greedy frontier exploration within reach of the base station (the original's
    RangeConstrained)."""

    name = "range_constrained"
    Params: ClassVar[type[StrategyParams]] = RangeConstrainedParams

    def __init__(self, params: RangeConstrainedParams) -> None:
        parts = default_parts(params)
        super().__init__(params, replace(parts, filter=NearBase(params.range)))


@STRATEGIES.register
class PeriodicReturn(FrontierExploration):
    """Greedy frontier exploration that reports to the base every ``period`` steps out of
    contact (the original's PeriodicReturn)."""

    name = "periodic_return"
    Params: ClassVar[type[StrategyParams]] = PeriodicReturnParams
    params: PeriodicReturnParams

    def decide(self, view: RobotView) -> Decision:
        """Head for the base while its report is due, else explore as ``frontier``."""
        if view.step - view.base_contact >= self.params.period:
            context = plan_context(view)
            return heading_for(context, view.base_position, info={"reason": REPORT})
        return super().decide(view)


REPORT = "periodic report"  # Decision.info["reason"] of a robot going back to report


@dataclass
class PotentialChoice:
    """The frontier where the attractive potential (size / path cost, scaled to the best
    one's) less the teammates' repulsive potential (``weight * (1 - gap / radius)`` for
    each teammate nearer than ``radius`` to its target) is highest."""

    radius: float | None
    weight: float
    teammate_memory: int

    def choose(self, offer: Offer) -> int:
        """The candidate of highest potential."""
        candidates = offer.candidates
        sizes = offer.frontiers.sizes[candidates].astype(float)
        costs = np.maximum(offer.costs[candidates], 1.0)
        pull = sizes / costs
        pull = pull / pull.max()
        radius = self.radius or offer.view.sensor_range / 4
        goals = offer.targets[candidates].astype(float) + 0.5  # (row, col) centres
        push = np.zeros(len(candidates))
        for mate in auction_team(offer.view, self.teammate_memory):
            gap = np.hypot(goals[:, 1] - mate.position[0], goals[:, 0] - mate.position[1])
            push += np.clip(1.0 - gap / radius, 0.0, None)
        return int(candidates[int(np.argmax(pull - self.weight * push))])


@STRATEGIES.register
class PotentialField(FrontierExploration):
    """Frontiers attract, teammates repel (after MMPF)."""

    name = "potential_field"
    Params: ClassVar[type[StrategyParams]] = PotentialFieldParams

    def __init__(self, params: PotentialFieldParams) -> None:
        choice = PotentialChoice(params.repulsion, params.repulsion_weight, params.teammate_memory)
        super().__init__(params, replace(default_parts(params), allocation=choice))


@STRATEGIES.register
class NearestFrontier(FrontierExploration):
    """Uncoordinated nearest-frontier exploration (Yamauchi 1998)."""

    name = "nearest_frontier"
    Params: ClassVar[type[StrategyParams]] = NearestFrontierParams

    def __init__(self, params: NearestFrontierParams) -> None:
        super().__init__(params, nearest_parts())


@STRATEGIES.register
class VoronoiExploration(FrontierExploration):
    """Each robot explores the frontiers of its own Voronoi cell, nearest first."""

    name = "voronoi"
    Params: ClassVar[type[StrategyParams]] = VoronoiParams

    def __init__(self, params: VoronoiParams) -> None:
        super().__init__(params, nearest_parts(VoronoiCell(params.teammate_memory)))
