"""Metrics (phase 7) for a world that changes: explored and stale cells from robots' current maps.

With 'latest' beliefs (``simulation.belief``) a robot's map can lose a FREE cell (a
person stepped in, a door closed: its newer observation wins), and the truth can
change under the maps. The explored metric then counts, among the explorable cells of
this step's truth (``world.explorable``; and, for ``explored_connected``, among its free
cells 4-connected to the starts), those that at least one robot's *current* map holds
FREE; ``stale`` counts the cells on which at least one robot's current map disagrees
with the truth of this step: held FREE but now an obstacle, or held OCCUPIED but now
free (a person who walked on, a door that opened).

Both follow every change incrementally, like :class:`~mresim_phys.knowledge.mapping.
Coverage`: robots report the windows their scans touched and the boxes their merges
changed (:meth:`LatestCoverage.touch_box`), the world reports where the truth or the
counted sets changed (:meth:`LatestCoverage.retarget`); only those windows are
recounted. A per-robot copy of which cells it held FREE / OCCUPIED turns a window of
its map into changes of the per-cell holder counts. One compiled pass per window
(:func:`fold_window`) folds a map's window and recounts it.

Each agent's observation steps are the feature :data:`LATEST` (``features.py``; the base
station has it too): with 'latest' beliefs, ``Agent.features["observed"]`` is the step of
each cell's latest observation (-1: never), which its scans stamp and the comm exchange's
merge reads (the newer observation wins). Its strategy sees it read-only; snapshots and
logs do not carry it.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

from mresim_phys.features import ReadOnlyGrid
from mresim_phys.knowledge.coverage import Coverage
from mresim_phys.knowledge.mapping import Update
from mresim_phys.memory import sparse_zeros
from mresim_phys.types import FREE, OCCUPIED, BeliefGrid, BoolGrid

Box = tuple[int, int, int, int]  # row0, row1, col0, col1 (half-open)
Stamps = NDArray[np.int32]  # per cell, the step of its latest observation (-1: never)


class LatestObservations(ReadOnlyGrid[Stamps]):
    """When an agent last observed each cell ('latest' beliefs; module docstring); its
    strategy sees them read-only."""

    key = "observed"
    recorded = False


LATEST = LatestObservations()


def give_stamps(states: dict[str, object], shape: tuple[int, int]) -> None:
    """Keep the latest observation of every cell of a map of ``shape`` (none yet)."""
    states[LATEST.key] = np.full(shape, -1, dtype=np.int32)


class LatestCoverage(Coverage):
    """Explored (counted truth-free cells some robot now holds FREE) and stale cells."""

    def __init__(
        self, reachable: BoolGrid, truth: BoolGrid, connected: BoolGrid | None = None
    ) -> None:
        super().__init__(reachable, connected)
        self.truth = truth  # the world's truth grid, changed in place by the world
        self.free_holders = np.zeros(truth.shape, dtype=np.uint16)
        self.wall_holders = np.zeros(truth.shape, dtype=np.uint16)
        self._held: dict[int, BeliefGrid] = {}  # each map as last folded in
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
            self._held[id(belief)] = sparse_zeros(belief.shape, np.uint8)  # UNKNOWN
        rows, cols = window
        held = self._held[id(belief)]
        second = self.reachable if self.connected is None else self.connected
        counted, counted_second, stale = fold_window(
            belief, held, words(belief), words(held), self.free_holders, self.wall_holders,
            self.known, self.reachable, second, self.truth, self.stale_mask,
            rows.start, rows.stop, cols.start, cols.stop,
        )  # fmt: skip
        self.count += counted
        self.count_connected += counted_second if self.connected is not None else 0
        self.stale += stale

    def retarget(
        self, reachable: BoolGrid, window: Box | None = None, before: BoolGrid | None = None
    ) -> None:
        """The truth changed (inside ``window``, or anywhere): count against it."""
        super().retarget(reachable, window, before)
        rows, cols = self.truth.shape
        r0, r1, c0, c1 = window if window is not None else (0, rows, 0, cols)
        region = (slice(r0, r1), slice(c0, c1))
        stale = (self.known[region] & self.truth[region]) | (
            (self.wall_holders[region] > 0) & ~self.truth[region]
        )
        self.stale += int(np.count_nonzero(stale)) - int(np.count_nonzero(self.stale_mask[region]))
        self.stale_mask[region] = stale


WORD = 8  # cells compared at once (a uint64 of a uint8 map)


def words(grid: BeliefGrid) -> np.ndarray:
    """``grid`` (uint8, C-contiguous) seen as rows of uint64 words of 8 cells; an empty
    (rows, 0) array when its rows are not a whole number of words (then cells are
    compared one at a time)."""
    if grid.shape[1] % WORD or not grid.flags.c_contiguous:
        return np.zeros((grid.shape[0], 0), np.uint64)
    return grid.view(np.uint64)


@njit(cache=True, nogil=True)
def fold_window(
    belief: BeliefGrid,
    held: BeliefGrid,
    belief_words: np.ndarray,
    held_words: np.ndarray,
    free_holders: np.ndarray,
    wall_holders: np.ndarray,
    known: BoolGrid,
    reachable: BoolGrid,
    connected: BoolGrid,
    truth: BoolGrid,
    stale_mask: BoolGrid,
    row0: int,
    row1: int,
    col0: int,
    col1: int,
) -> tuple[int, int, int]:
    """Fold one map's window into the holder counts (what it holds now against what it
    held when last folded, ``held``, updated in place), recounting ``known`` and
    ``stale_mask`` on the cells whose value changed (elsewhere they are up to date:
    :meth:`LatestCoverage.retarget` follows the truth); returns the change of the
    explored count (cells of ``reachable``), of the count over ``connected`` and of the
    stale count.

    With word views of both maps (:func:`words`), runs of 8 unchanged cells are skipped
    with one comparison (most of a window is unchanged: ~5x faster on the library);
    cells are still visited in raster order, so the result is the same."""
    counted = counted_connected = 0
    stale_change = 0
    whole = belief_words.shape[1] > 0
    for r in range(row0, row1):
        c = col0
        while c < col1:
            word = c // WORD
            if (
                whole
                and c % WORD == 0
                and c + WORD <= col1
                and belief_words[r, word] == held_words[r, word]
            ):
                c += WORD
                continue
            value, old = belief[r, c], held[r, c]
            if value != old:
                held[r, c] = value
                free_holders[r, c] += (value == FREE) - (old == FREE)
                wall_holders[r, c] += (value == OCCUPIED) - (old == OCCUPIED)
                now = free_holders[r, c] > 0
                if reachable[r, c]:
                    counted += int(now) - int(known[r, c])
                if connected[r, c]:
                    counted_connected += int(now) - int(known[r, c])
                known[r, c] = now
                stale = (now and truth[r, c]) or (wall_holders[r, c] > 0 and not truth[r, c])
                stale_change += int(stale) - int(stale_mask[r, c])
                stale_mask[r, c] = stale
            c += 1
    return counted, counted_connected, stale_change
