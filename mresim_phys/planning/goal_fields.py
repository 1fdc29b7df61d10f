"""Phase 4b (planning): searches from the auction's goals, shared by every teammate's bid.

The frontier auction needs the path cost of a (teammate, goal) pair only to know whether
that pair beats the others. A teammate's own search (``planning.goals``) gives the exact
cost, one teammate at a time; a search from the goal gives every teammate's cost at once,
to within rounding: path costs on one passable mask are symmetric (the moves and the
corner rule are the same both ways), but a cost is a float sum of the moves taken in order,
and the reverse order can round differently. A cost is the least such sum over the paths
(the distance field's fixed point, whatever order cells were expanded in), so the two
differ by at most the rounding of a sum of ``c`` moves of at most ``c`` each:
``c**2 * 2**-53``, well under the margin allowed (``1e-9 * (1 + c)``) up to costs of ~9e6.

So :class:`GoalFields` narrows each teammate's bounds to an interval holding its exact cost,
or raises its lower bound where the goal's search has not reached it yet. The searches
pause (``dial``) and go on when the auction asks for more; each runs in a window around its
goal, grown (searched again) when a farther teammate is asked for, so that a near goal
costs a near search.

Where two bids are closer than the bounds can tell (teammates as far from a goal as each
other), :meth:`GoalFields.exact_cost` finds a teammate's exact cost by an A* from its cell
steered by the goal's search (``bestfirst.guided``): the same fixed point, so the same
float as its own search, but expanded along the near-best paths only.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numba import njit
from numpy.typing import NDArray

from mresim_phys.planning.astar import NO_ALLOWED, NO_LABELS
from mresim_phys.planning.bestfirst import astar_kernel
from mresim_phys.planning.dial import PausedSearch
from mresim_phys.planning.fields import MAX_SNAP, _window, snap_to_passable
from mresim_phys.planning.grid import Box, Window, search_arrays
from mresim_phys.types import BoolGrid, FloatArray, IntArray

RELATIVE_ROUNDING = 1e-9  # of a cost: what a sum of moves in another order may round away
GROWTH = 1.5  # a window searched again grows to at least this multiple of its reach
SMALLEST_REACH = 16  # cells: the first window's least reach around its goal


def standing_cells(
    passable: BoolGrid, positions: Sequence[tuple[float, float]], max_snap: float = MAX_SNAP
) -> IntArray:
    """Each world position's cell as a search from it starts there (``snap_to_passable``),
    rows of (row, col); (-1, -1) where there is none."""
    xy = np.array(positions, dtype=np.float64).reshape(-1, 2)
    cells = np.floor(xy[:, ::-1]).astype(np.int64)
    rows, cols = passable.shape
    inside = (cells[:, 0] >= 0) & (cells[:, 0] < rows) & (cells[:, 1] >= 0) & (cells[:, 1] < cols)
    on = np.zeros(len(cells), dtype=bool)
    on[inside] = passable[cells[inside, 0], cells[inside, 1]]
    for i in np.flatnonzero(~on):
        snapped = snap_to_passable(passable, (float(xy[i, 0]), float(xy[i, 1])), max_snap)
        cells[i] = (-1, -1) if snapped is None else snapped
    return cells


@dataclass
class _GoalSearch:
    """A paused search from one goal cell in a window of ``reach`` around it (the whole box
    when ``reach`` is inf); costs below ``reach`` are the box's."""

    search: PausedSearch
    reach: float
    nodes: IntArray  # each teammate's window node (-1: off the window or no cell)

    @classmethod
    def around(
        cls, passable: BoolGrid, box: Box, goal: tuple[int, int], reach: int, cells: IntArray
    ) -> _GoalSearch:
        window = _window(goal, box, reach)
        search = PausedSearch(passable, goal, window)
        whole = window == box
        rows = cells[:, 0] - search.window.origin[0]
        cols = cells[:, 1] - search.window.origin[1]
        hp = search.window.pad.size // search.window.wp
        inside = (cells[:, 0] >= 0) & (rows >= 0) & (rows < hp) & (cols >= 0)
        inside &= cols < search.window.wp
        nodes = np.where(inside, rows * search.window.wp + cols, -1)
        return cls(search, np.inf if whole else float(reach), nodes)

    @property
    def settled_below(self) -> float:
        """Costs below this are the goal's exact (reverse) costs on the whole box."""
        return min(self.search.settled_below, self.reach)


@dataclass
class GoalFields:
    """Searches from the goals ``goals_rc`` (rows of (row, col)) on ``passable`` (``box``:
    its bounding box, as the teammates' own searches use it), for teammates standing on
    ``cells`` (rows of (row, col), (-1, -1) for a teammate with no passable cell, whose
    bounds stay unknown)."""

    passable: BoolGrid
    box: Box
    goals_rc: IntArray
    cells: IntArray
    _searches: dict[int, _GoalSearch] = field(default_factory=dict)
    _exact: dict[tuple[int, int, int], float] = field(default_factory=dict)

    @classmethod
    def for_auction(
        cls,
        passable: BoolGrid,
        box: Box,
        goals_rc: IntArray,
        positions: Sequence[tuple[float, float]],
    ) -> GoalFields:
        """The searches of an auction whose bidder 0 is the robot itself (it bids its exact
        costs: no cell) and bidders 1 on the teammates at world ``positions``."""
        cells = np.vstack([[[-1, -1]], standing_cells(passable, positions)]).astype(np.int64)
        return cls(passable, box, goals_rc, cells)

    def tighten(
        self,
        goal: int,
        who: int,
        limit: float,
        costs: FloatArray,
        high: FloatArray,
        exact: NDArray[np.bool_],
    ) -> None:
        """Raise the lower bounds ``costs[i, goal]`` and lower the upper bounds
        ``high[i, goal]`` of every teammate ``i`` whose cost is not ``exact``, after the
        goal's search has expanded the costs below ``limit``, or sooner, once teammate
        ``who``'s is final. A teammate the whole search never reached cannot reach the goal:
        its cost becomes exact, inf."""
        has_cell = self.cells[:, 0] >= 0
        rc = (int(self.goals_rc[goal, 0]), int(self.goals_rc[goal, 1]))
        if not self._passable(rc):  # no teammate's own search ever reaches it
            out = has_cell & ~exact[:, goal]
            costs[out, goal] = high[out, goal] = np.inf
            exact[out, goal] = True
            return
        found = self._search(goal, rc, limit)
        found.search.run_below(limit, int(found.nodes[who]))
        _tighten(found.search.dist, found.nodes, has_cell, found.settled_below, costs, high,
                 exact, goal)  # fmt: skip

    def exact_cost(self, goal: int, who: int, limit: float) -> float | None:
        """Teammate ``who``'s exact path cost to ``goal`` (the float its own search would
        find) when it is at most ``limit``: an A* from its cell steered by the goal's
        search (``bestfirst.guided``), in the window of cells within ``limit`` of it, as
        its own search would run. None where this cannot tell: the teammate has no cell,
        the goal no search yet, or the cost is above ``limit``. Teammates on one cell share
        the answer."""
        row, col = int(self.cells[who, 0]), int(self.cells[who, 1])
        found = self._searches.get(goal)
        if row < 0 or found is None:
            return None
        key = (row, col, goal)
        cost = self._exact.get(key)
        if cost is None:
            cost = _steered(self.passable, self.box, (row, col), found, limit)
            if cost <= limit:  # above it the window was too small to say how much more
                self._exact[key] = cost
        return cost if cost <= limit else None

    def _passable(self, rc: tuple[int, int]) -> bool:
        r0, r1, c0, c1 = self.box
        return r0 <= rc[0] < r1 and c0 <= rc[1] < c1 and bool(self.passable[rc])

    def _search(self, goal: int, rc: tuple[int, int], limit: float) -> _GoalSearch:
        """The goal's search, in a window that holds every cost below ``limit``."""
        found = self._searches.get(goal)
        if found is not None and found.reach >= limit:
            return found
        grown = limit if found is None else max(limit, GROWTH * found.reach)
        extent = max(self.box[1] - self.box[0], self.box[3] - self.box[2])
        reach = extent if grown >= extent else max(int(np.ceil(grown)), SMALLEST_REACH)
        found = _GoalSearch.around(self.passable, self.box, rc, reach, self.cells)
        self._searches[goal] = found
        return found


def _steered(
    passable: BoolGrid, box: Box, start: tuple[int, int], goal: _GoalSearch, limit: float
) -> float:
    """The path cost from ``start`` to the cell ``goal`` searches from, by an A* steered
    by that search, in ``box`` cut to the cells within ``limit`` of ``start``; inf where the
    goal lies outside that window or cannot be reached in it."""
    window = Window.around(passable, _window(start, box, limit))
    target = window.node_inside(goal.search.start)
    if target is None:
        return np.inf
    frame = goal.search.window
    guide = (
        goal.search.dist, window.origin[0] - frame.origin[0], window.origin[1] - frame.origin[1],
        frame.wp, frame.pad.size // frame.wp, float(goal.settled_below),
    )  # fmt: skip
    g, pred, state = search_arrays(window.pad.size)
    cost, _ = astar_kernel(
        window.pad, window.wp, window.node(start), target, NO_LABELS, NO_ALLOWED, None, g,
        pred, state, guide,
    )  # fmt: skip
    return float(cost)


@njit(cache=True, nogil=True)
def _tighten(
    dist: FloatArray,
    nodes: IntArray,
    has_cell: NDArray[np.bool_],
    below: float,
    costs: FloatArray,
    high: FloatArray,
    exact: NDArray[np.bool_],
    goal: int,
) -> None:
    """:meth:`GoalFields.tighten` for a search's costs ``dist`` (teammate ``i`` at node
    ``nodes[i]``, -1 off the window), final below ``below``: a reached teammate's cost lies
    within ``RELATIVE_ROUNDING * (1 + cost)`` of its reverse cost, the others' at least
    ``below`` (less that margin), and with ``below`` inf they cannot reach the goal."""
    for i in range(len(nodes)):
        if not has_cell[i] or exact[i, goal]:
            continue
        cost = dist[nodes[i]] if nodes[i] >= 0 else np.inf
        if cost < below:
            margin = RELATIVE_ROUNDING * (1.0 + cost)
            costs[i, goal] = max(costs[i, goal], cost - margin)
            high[i, goal] = min(high[i, goal], cost + margin)
        elif below == np.inf:
            costs[i, goal], high[i, goal], exact[i, goal] = np.inf, np.inf, True
        else:
            costs[i, goal] = max(costs[i, goal], below - RELATIVE_ROUNDING * (1.0 + below))
