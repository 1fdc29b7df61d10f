"""The frontier auction (phase 4, decide): which frontier a robot wins against its teammates.

The original's greedy auction: the best (robot, frontier) pair by utility
``U = size * 1e8 / d**4`` is fixed, that robot and that frontier leave the auction, until
the best pair is the deciding robot's. The robot knows its own path costs; a teammate bids
with lower bounds (the straight line from its last known position, raised by the triangle
inequality through the robot's own search: :func:`path_bounds`). Before a bound can win it
is narrowed by a search from the goal (``planning.goal_fields``: every teammate's cost within
rounding at once), and replaced by the exact path cost on the robot's map only where the
narrowed bounds cannot tell two bids apart: by an A* steered by the goal's search
(``GoalFields.exact_cost``), or the teammate's own search (``planning.goals``) where that
cannot tell.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from numba import njit
from numpy.typing import NDArray

from mresim_phys.planning.dial import PausedSearch
from mresim_phys.planning.fields import MAX_SNAP, snap_to_passable
from mresim_phys.planning.goal_fields import GoalFields
from mresim_phys.planning.goals import GoalCosts, goal_costs
from mresim_phys.strategies.base import PlanContext
from mresim_phys.strategies.frontier_utility import pair_utilities, utility
from mresim_phys.types import FloatArray, IntArray

MIN_SEARCH = 10.0  # cells: smallest extra horizon when refining a teammate's bid
SEARCH_GROWTH = 1.5  # a refinement searches to this multiple of the current lower bound
MAX_BOUNDED_SEARCH = 2000.0  # cells: beyond this a teammate's search is unbounded
BoolArray = NDArray[np.bool_]
PathSearch = Callable[["Bidder", int, float], "GoalCosts | None"]


@dataclass
class Bidder:
    """One robot in the auction: lower bounds on its path costs, and which are exact."""

    name: str
    costs: FloatArray
    exact: BoolArray
    position: tuple[float, float]
    rank: int = 0  # the team's tie-break order: of two equal bids the lower rank wins

    @classmethod
    def estimated(
        cls,
        name: str,
        position: tuple[float, float],
        goals_rc: IntArray,
        rank: int = 0,
        bounds: FloatArray | None = None,
    ) -> Bidder:
        """A teammate bidding with lower bounds on its path costs: straight-line distances,
        or ``bounds`` where those are higher (:func:`path_bounds`)."""
        costs = straight_line(position, goals_rc)
        if bounds is not None:
            costs = np.maximum(costs, bounds)
        return cls(name, costs, np.zeros(len(costs), dtype=bool), position, rank)


def straight_line(position: tuple[float, float], goals_rc: IntArray) -> FloatArray:
    """Straight-line distance from the centre of ``position``'s cell to each goal cell centre.

    Path costs run from cell centre to cell centre, so this is a true lower bound of
    the teammate's path cost: its bid is refined before it can lose a tie it would win.
    """
    col, row = np.floor(position[0]), np.floor(position[1])
    distance: FloatArray = np.hypot(goals_rc[:, 1] - col, goals_rc[:, 0] - row)
    return distance


BOUND_MARGIN = 1e-6  # cells: what a lower bound from two float path costs gives up


def path_bounds(
    search: PausedSearch | None, position: tuple[float, float], mine: FloatArray
) -> FloatArray | None:
    """Lower bounds on a teammate's path costs to the goals, from this robot's own search
    (``mine``: its exact costs to the goals; None without a search, or where the teammate
    stands on no passable cell of its window).

    Path costs on one passable mask are a metric (moves and the corner rule are the same
    both ways), so cost(teammate, goal) >= |cost(me, teammate) - cost(me, goal)|; where the
    search has not settled the teammate's cell, cost(me, teammate) >= its ``final_below``.
    A margin covers the two costs' float rounding. Bounds only decide which teammates the
    auction searches for: the winner depends on exact costs alone."""
    if search is None:
        return None
    node = search.window.node_inside((int(np.floor(position[1])), int(np.floor(position[0]))))
    if node is None or not search.window.pad[node]:
        return None
    here = float(search.dist[node])
    if here < search.final_below:
        bounds: FloatArray = np.abs(here - mine) - BOUND_MARGIN
    else:
        bounds = search.final_below - mine - BOUND_MARGIN
    return bounds


def teammate_bidders(
    names: Sequence[str],
    positions: Sequence[tuple[float, float]],
    ranks: Sequence[int],
    goals_rc: IntArray,
    search: PausedSearch | None,
    mine: FloatArray,
) -> list[Bidder]:
    """``Bidder.estimated(name, position, goals_rc, rank, path_bounds(search, position,
    mine))`` for every teammate, the straight lines and bounds of all of them computed
    together: the same floats, element by element, for one array operation instead of a
    few per teammate (a replan at 32 robots has 31 teammates)."""
    if len(names) == 0:
        return []
    xy = np.array(positions, dtype=np.float64).reshape(-1, 2)
    cols, rows = np.floor(xy[:, 0]), np.floor(xy[:, 1])
    costs = np.hypot(goals_rc[None, :, 1] - cols[:, None], goals_rc[None, :, 0] - rows[:, None])
    if search is not None:
        window = search.window
        r = rows.astype(np.int64) - window.origin[0]
        c = cols.astype(np.int64) - window.origin[1]
        inside = (r >= 0) & (r < window.pad.size // window.wp) & (c >= 0) & (c < window.wp)
        node = np.where(inside, r * window.wp + c, 0)
        on = inside & window.pad[node]
        here = search.dist[node[on]][:, None]
        settled = here < search.final_below
        bounds = np.where(
            settled, np.abs(here - mine) - BOUND_MARGIN, search.final_below - mine - BOUND_MARGIN
        )
        costs[on] = np.maximum(costs[on], bounds)
    exact = np.zeros(costs.shape, dtype=bool)  # one array: a row of it for each teammate
    return [
        Bidder(name, costs[i], exact[i], xy_i, rank)
        for i, (name, xy_i, rank) in enumerate(zip(names, positions, ranks, strict=True))
    ]


def exact_costs(
    context: PlanContext,
    position: tuple[float, float],
    goals_rc: IntArray,
    wanted: int,
    limit: float,
) -> GoalCosts | None:
    """Path costs on this robot's map from a teammate's position, searched up to ``limit``
    or until goal ``wanted``'s cost is known (None if the position is off the map)."""
    return goal_costs(
        context.passable, position, goals_rc, wanted, limit, context.passable_box,
        context.slowness,
    )  # fmt: skip


@dataclass
class TeammateSearches:
    """The teammates' own path searches of one auction (:func:`exact_costs`), kept by the
    cell each starts from: teammates on one cell (a team started on one spot) have the same
    exact costs, so a search from a cell answers every later question about a goal whose
    cost it found."""

    context: PlanContext
    goals_rc: IntArray
    done: dict[tuple[int, int], GoalCosts] = field(default_factory=dict)

    def __call__(self, bidder: Bidder, wanted: int, limit: float) -> GoalCosts | None:
        cell = snap_to_passable(self.context.passable, bidder.position, MAX_SNAP)
        before = None if cell is None else self.done.get(cell)
        if before is not None and (np.isfinite(before.found[wanted]) or before.floor == np.inf):
            return before
        found = exact_costs(self.context, bidder.position, self.goals_rc, wanted, limit)
        if cell is not None and found is not None:
            self.done[cell] = found
        return found


def greedy_auction(
    bidders: list[Bidder], sizes: FloatArray, search: PathSearch, fields: GoalFields | None = None
) -> int:
    """Index of the frontier bidder 0 wins in the greedy auction.

    Teammates bid with lower bounds (straight lines, raised by :func:`path_bounds`).
    A pair whose cost is only a lower bound is refined before it can win: the
    teammate's path search runs to 1.5 times the bound (at least ``MIN_SEARCH``
    cells more), so a teammate far away by path is ruled out by a small search, which
    stops once the pair's cost is final (``planning.goals``). With ``fields``
    (``planning.goal_fields``) the search runs from the goal instead, and bounds every
    teammate's cost to it at once, each within rounding once reached: a pair so bounded
    wins without its own search when even its highest cost beats every other pair's
    lowest; when the bounds cannot tell it from another, an A* steered by the goal's search
    finds its exact cost (the same float as the teammate's own search, which stays the
    fallback).
    Which pair wins depends only on the exact costs (lower bounds never win: they are
    refined first, and a bound's utility is never below its exact one), so how far a
    search went never changes it. Utilities are one (bidders x frontiers) matrix; a
    refinement recomputes what it changed.
    When every frontier is taken before bidder 0 wins one, the auction starts again
    over all the frontiers among the bidders not yet assigned (the original's
    ``keepAssigningRobotsToFrontiers``), so robots that outnumber the frontiers
    spread over them instead of all following the best one.
    """
    bids = Bids.of(bidders, sizes)
    try:
        return bids.run(bidders, search, fields)
    finally:
        for bidder, costs, exact in zip(bidders, bids.costs, bids.exact, strict=True):
            bidder.costs, bidder.exact = costs.copy(), exact.copy()


@dataclass
class Bids:
    """The auction's state: every pair's lower bound (``costs``), upper bound (``high``,
    inf: none) and whether the cost is exact; the utilities of both bounds (``u`` of the
    lower, ``u_low`` of the upper: -inf where there is none)."""

    sizes: FloatArray
    costs: FloatArray
    high: FloatArray
    exact: BoolArray
    ranks: IntArray
    u: FloatArray
    u_low: FloatArray

    @classmethod
    def of(cls, bidders: list[Bidder], sizes: FloatArray) -> Bids:
        costs = np.array([b.costs for b in bidders], dtype=np.float64)
        exact = np.array([b.exact for b in bidders], dtype=bool)
        ranks = np.array([b.rank for b in bidders], dtype=np.int64)
        high = np.where(exact, costs, np.inf)
        u = utility(sizes[None, :], costs)
        # utility(high) without a second pass of powers: where a cost is exact its upper
        # bound is the cost itself (the same element of a matrix of the same shape: the
        # same float), elsewhere there is no upper bound (-inf)
        return cls(sizes, costs, high, exact, ranks, u, np.where(exact, u, -np.inf))

    def run(self, bidders: list[Bidder], search: PathSearch, fields: GoalFields | None) -> int:
        """The greedy auction over these bids (:func:`greedy_auction`)."""
        active = np.ones(len(self.costs), dtype=bool)
        taken = np.zeros(len(self.sizes), dtype=bool)
        while True:
            who, which = assign(self.u, self.u_low, self.exact, self.ranks, active, taken)
            if who == 0:
                return which
            if who < 0:
                return int(np.argmax(self.u[0]))
            self._refine(bidders[who], who, which, search, fields)

    def _refine(
        self, bidder: Bidder, who: int, which: int, search: PathSearch, fields: GoalFields | None
    ) -> None:
        bound = float(self.costs[who, which])
        limit = max(SEARCH_GROWTH * bound, bound + MIN_SEARCH)
        limit = np.inf if limit > MAX_BOUNDED_SEARCH else limit
        if fields is not None and self.high[who, which] == np.inf and fields.cells[who, 0] >= 0:
            fields.tighten(which, who, limit, self.costs, self.high, self.exact)
            self._rescore(slice(None), which)
            return
        if self.high[who, which] < np.inf:  # bounded both ways: the exact cost is below
            limit = float(self.high[who, which])
            steered = None if fields is None else fields.exact_cost(which, who, limit)
            if self._settle(who, which, steered):
                return
        self._row(who, search(bidder, which, limit))
        if not self.exact[who, which]:  # bounds that did not hold (cannot happen): search on
            self._row(who, search(bidder, which, np.inf))

    def _settle(self, who: int, which: int, cost: float | None) -> bool:
        """Take a pair's exact cost (None: not known; nothing changes); whether it was."""
        if cost is None:
            return False
        self.costs[who, which] = self.high[who, which] = cost
        self.exact[who, which] = True
        self._rescore(slice(who, who + 1), which)
        return True

    def _rescore(self, rows: slice, which: int) -> None:
        """The utilities of both bounds of the pairs (``rows``, ``which``), after a
        refinement moved them (one compiled pass: :func:`pair_utilities`)."""
        pair_utilities(
            float(self.sizes[which]), self.costs[rows, which], self.high[rows, which],
            self.u[rows, which], self.u_low[rows, which],
        )  # fmt: skip

    def _row(self, who: int, searched: GoalCosts | None) -> None:
        """Take the exact path costs a teammate's own search found; the bounds of the
        others rise to its floor. Costs known exactly before stay (the same search from
        the same cell). A teammate standing where this robot knows nothing (None) keeps
        its estimates, as exact."""
        costs, exact = self.costs[who], self.exact[who]
        if searched is None:
            exact[:] = True
        else:
            known = np.isfinite(searched.found) | (searched.floor == np.inf)
            raised = np.where(exact, costs, np.maximum(costs, searched.floor))
            costs[:] = np.where(known, searched.found, raised)
            exact |= known
        self.high[who] = np.where(exact, costs, self.high[who])
        self.u[who] = utility(self.sizes, costs)
        self.u_low[who] = utility(self.sizes, self.high[who])


@njit(cache=True, nogil=True)
def assign(
    u: FloatArray,
    u_low: FloatArray,
    exact: BoolArray,
    ranks: IntArray,
    active: BoolArray,
    taken: BoolArray,
) -> tuple[int, int]:
    """Assign the best pairs (:func:`best_pair`) until bidder 0 wins one, (0, frontier), or
    a pair must be refined first, (bidder, frontier); (-1, -1) when no pair is left. A pair
    is fixed when its cost is exact, or when its lowest utility (``u_low``) beats every
    other open pair's highest (``u``). ``active`` and ``taken`` carry the state between
    calls (a refinement changes only bounds)."""
    while active.any():
        if taken.all():  # more robots than frontiers: a new round for the unassigned
            taken[:] = False
        who, which = best_pair(u, ranks, active, taken)
        if who < 0:
            break
        if not exact[who, which]:
            low = u_low[who, which]
            if low == -np.inf or not beats_the_rest(u, active, taken, who, which, low):
                return who, which
        if who == 0:
            return who, which
        active[who] = False
        taken[which] = True
    return -1, -1


@njit(cache=True, nogil=True)
def best_pair(
    u: FloatArray, ranks: IntArray, active: BoolArray, taken: BoolArray
) -> tuple[int, int]:
    """The (bidder, frontier) pair of highest utility in ``u`` among active bidders and
    frontiers not taken; (-1, -1) if none is left.

    Each bidder bids for its best frontier (the first of equal ones); equal bids go
    to the bidder of lower rank (then the earlier bidder), so robots that see the same
    bids (robots started on one spot) agree on who wins instead of each taking the tie.
    One compiled pass (comparisons only: the utilities are numpy's).
    """
    who, which, top, top_rank = -1, -1, -np.inf, 0
    for i in range(u.shape[0]):
        if not active[i]:
            continue
        bid, pick = -np.inf, -1
        for j in range(u.shape[1]):
            if not taken[j] and u[i, j] > bid:
                bid, pick = u[i, j], j
        if bid > top or (bid == top and bid > -np.inf and ranks[i] < top_rank):
            who, which, top, top_rank = i, pick, bid, ranks[i]
    return who, which


@njit(cache=True, nogil=True)
def beats_the_rest(
    u: FloatArray, active: BoolArray, taken: BoolArray, who: int, which: int, bid: float
) -> bool:
    """Whether ``bid`` beats (strictly) the utility of every open pair but (who, which)."""
    for i in range(u.shape[0]):
        if not active[i]:
            continue
        for j in range(u.shape[1]):
            if not taken[j] and (i != who or j != which) and u[i, j] >= bid:
                return False
    return True
