"""Metrics (phase 7) for a world that changes: explored and stale cells from robots' current maps.

With 'latest' beliefs (``simulation.belief``) a robot's map can lose a FREE cell (a
person stepped in, a door closed: its newer observation wins), and the truth can
change under the maps. The explored metric then counts, among the free cells of the
truth of this step that are reachable from the starts, those that at least one
robot's *current* map holds FREE; ``stale`` counts the cells on which at least one
robot's current map disagrees with the truth of this step: held FREE but now an
obstacle, or held OCCUPIED but now free (a person who walked on, a door that opened).

Both follow every change incrementally, like :class:`~mresim_phys.knowledge.mapping.
Coverage`: robots report the windows their scans touched and the boxes their merges
changed (:meth:`LatestCoverage.touch_box`), the world reports where the truth or the
reachable set changed (:meth:`LatestCoverage.retarget`); only those windows are
recounted. A per-robot copy of which cells it held FREE / OCCUPIED turns a window of
its map into changes of the per-cell holder counts.
"""

from __future__ import annotations

import numpy as np

from mresim_phys.knowledge.mapping import Coverage, Update
from mresim_phys.types import FREE, OCCUPIED, BeliefGrid, BoolGrid

Box = tuple[int, int, int, int]  # row0, row1, col0, col1 (half-open)


class LatestCoverage(Coverage):
    """Explored (reachable truth-free cells some robot now holds FREE) and stale cells."""

    def __init__(self, reachable: BoolGrid, truth: BoolGrid) -> None:
        super().__init__(reachable)
        self.truth = truth  # the world's truth grid, changed in place by the world
        self.free_holders = np.zeros(truth.shape, dtype=np.uint16)
        self.wall_holders = np.zeros(truth.shape, dtype=np.uint16)
        self._held: dict[int, tuple[BoolGrid, BoolGrid]] = {}
        self._boxes: dict[int, tuple[BeliefGrid, Box]] = {}
        self.stale_mask = np.zeros(truth.shape, dtype=bool)
        self.stale = 0

    def touch(self, belief: BeliefGrid, update: Update) -> None:
        """Remember that ``update``'s window of ``belief`` changed this step."""
        h, w = update.free.shape
        self.touch_box(belief, (update.row0, update.row0 + h, update.col0, update.col0 + w))

    def touch_box(self, belief: BeliefGrid, box: Box) -> None:
        """Remember that ``belief`` may have changed inside ``box`` this step."""
        held = self._boxes.get(id(belief))
        if held is not None:
            a = held[1]
            box = (min(a[0], box[0]), max(a[1], box[1]), min(a[2], box[2]), max(a[3], box[3]))
        self._boxes[id(belief)] = (belief, box)

    def settle(self) -> None:
        """Recount the touched windows of every map."""
        for belief, (r0, r1, c0, c1) in self._boxes.values():
            self._fold(belief, (slice(r0, r1), slice(c0, c1)))
        self._boxes.clear()

    def _fold(self, belief: BeliefGrid, window: tuple[slice, slice]) -> None:
        """Move one map's window into the holder counts and recount the window."""
        if id(belief) not in self._held:
            shape = belief.shape
            self._held[id(belief)] = (np.zeros(shape, bool), np.zeros(shape, bool))
        held_free, held_wall = self._held[id(belief)]
        free, wall = belief[window] == FREE, belief[window] == OCCUPIED
        self.free_holders[window] += free
        self.free_holders[window] -= held_free[window]
        self.wall_holders[window] += wall
        self.wall_holders[window] -= held_wall[window]
        held_free[window], held_wall[window] = free, wall
        self._recount(window)

    def _recount(self, window: tuple[slice, slice]) -> None:
        """Recount explored and stale cells inside ``window``."""
        known = self.free_holders[window] > 0
        reach = self.reachable[window]
        old = self.known[window]
        self.count += int(np.count_nonzero(known & reach)) - int(np.count_nonzero(old & reach))
        self.known[window] = known
        truth = self.truth[window]
        stale = (known & truth) | ((self.wall_holders[window] > 0) & ~truth)
        self.stale += int(np.count_nonzero(stale)) - int(np.count_nonzero(self.stale_mask[window]))
        self.stale_mask[window] = stale

    def retarget(self, reachable: BoolGrid, window: Box | None = None) -> None:
        """The truth changed (inside ``window``, or anywhere): count against it."""
        super().retarget(reachable, window)
        rows, cols = self.truth.shape
        r0, r1, c0, c1 = window if window is not None else (0, rows, 0, cols)
        region = (slice(r0, r1), slice(c0, c1))
        stale = (self.known[region] & self.truth[region]) | (
            (self.wall_holders[region] > 0) & ~self.truth[region]
        )
        self.stale += int(np.count_nonzero(stale)) - int(np.count_nonzero(self.stale_mask[region]))
        self.stale_mask[region] = stale
