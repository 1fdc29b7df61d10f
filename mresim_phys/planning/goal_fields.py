"""Phase 4b (planning): searches from the auction's goals, shared by every teammate's bid.

The frontier auction needs the path cost of a (teammate, goal) pair only to know whether
that pair beats the others. A teammate's own search (``planning.goals``) gives the exact
cost, one teammate at a time; a search from the goal gives every teammate's cost at once,
to within rounding: path costs on one passable mask are symmetric (the moves and the
corner rule are the same both ways), but a cost is a float sum of the moves taken in order,
and the reverse order can round differently. A cost is the least such sum over the paths
(the distance field's fixed point, whatever order cells were expanded in), so the two
differ by at most the rounding of a sum of ``c`` moves of at most ``c`` each:
``c**2 * 2**-53``, well under :func:`rounding` (``1e-9 * (1 + c)``) up to costs of ~9e6.

So :class:`GoalFields` gives each teammate an interval holding its exact cost, or a lower
bound where the goal's search has not reached it yet. The searches pause (``dial``) and go
on when the auction asks for more; each runs in a window around its goal, grown (searched
again) when a farther teammate is asked for, so that a near goal costs a near search.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from mresim_phys.planning.dial import PausedSearch
from mresim_phys.planning.fields import MAX_SNAP, _window, snap_to_passable
from mresim_phys.planning.grid import Box
from mresim_phys.types import BoolGrid, FloatArray, IntArray

RELATIVE_ROUNDING = 1e-9  # of a cost: what a sum of moves in another order may round away
GROWTH = 1.5  # a window searched again grows to at least this multiple of its reach
SMALLEST_REACH = 16  # cells: the first window's least reach around its goal


def rounding(costs: FloatArray | float) -> FloatArray:
    """How far a path cost summed from the other end may lie from ``costs``."""
    return RELATIVE_ROUNDING * (1.0 + np.abs(np.asarray(costs, dtype=np.float64)))


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


@dataclass(frozen=True)
class Bounds:
    """What a goal's search tells of each teammate's path cost to the goal: it lies in
    ``[low, high]`` (``high`` inf: only the lower bound is known); where ``known``, it is
    inf exactly (the goal is unreachable from the teammate)."""

    low: FloatArray
    high: FloatArray
    known: NDArray[np.bool_]


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

    def bounds(self, goal: int, who: int, limit: float) -> Bounds:
        """Every teammate's bounds on its cost to ``goal`` after the goal's search has
        expanded the costs below ``limit``, or sooner, once teammate ``who``'s is final."""
        rc = (int(self.goals_rc[goal, 0]), int(self.goals_rc[goal, 1]))
        if not self._passable(rc):  # no teammate's search ever reaches it
            n = len(self.cells)
            return Bounds(np.full(n, np.inf), np.full(n, np.inf), self.cells[:, 0] >= 0)
        found = self._search(goal, rc, limit)
        found.search.run_below(limit, int(found.nodes[who]))
        return self._read(found)

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

    def _read(self, found: _GoalSearch) -> Bounds:
        below = found.settled_below
        has_cell = self.cells[:, 0] >= 0
        on = found.nodes >= 0
        cost = np.where(on, found.search.dist[np.maximum(found.nodes, 0)], np.inf)
        settled = on & (cost < below)
        low = np.full(len(cost), below - rounding(below) if below < np.inf else np.inf)
        high = np.full(len(cost), np.inf)
        low[settled] = cost[settled] - rounding(cost[settled])
        high[settled] = cost[settled] + rounding(cost[settled])
        low[~has_cell] = -np.inf
        return Bounds(low, high, has_cell & ~settled & (below == np.inf))
