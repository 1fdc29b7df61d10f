"""Knowledge ledger (phase 6, bookkeeping): what changed in whose map, and when.

Maps travel as deltas. Every agent's cells carry the *tick* at which they last
changed: tick ``2t + 1`` for what the agent sensed during step ``t``, ``2t + 2`` for
what it received in step ``t``'s exchange, ``NEVER`` (0) for a cell never stamped. For
every ordered pair the ledger keeps the tick up to which the receiver holds everything
the sender had (``synced[i, j]``, ``NEVER`` at first), so a transmission carries only
the cells whose tick is newer.
Occupancy grids only ever grow (UNKNOWN < FREE < OCCUPIED, safe space only gains
cells), which is why merging deltas ends in exactly the maps a full exchange
gives (tests/test_comms.py checks it step by step). With 'latest' beliefs a cell may
change back (a scan overwrites what it sees); every change of a value is stamped like
any other, and the value travels with the step of its observation, so a receiver keeps
whichever observation is newer (:func:`~mresim_phys.comms.deltas.latest_code`).

Changes are found without full-grid passes: the simulation reports the window
of every scan (:meth:`Ledger.note`), and each agent's windows are compared with
the copy taken at its last stamping; a short list of (tick, box) per agent tells a
transmission which part of the grid can hold newer cells.

Every per-cell grid starts as zeros (``NEVER``, and origin 0: the origin of a cell never
stamped is never read), so the operating system maps a page of it only when a cell in it is
first written: an agent's ledger takes memory for the part of the map it holds, not for the
whole map (a campus of 4000 x 4000 cells would cost 96 MB an agent otherwise).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from mresim_phys.comms.changelog import ChangeLog
from mresim_phys.comms.deltas import Cells, merge_cells, stamp_changes, tile_shape
from mresim_phys.memory import sparse_zeros
from mresim_phys.planning.grid import Box, union_box
from mresim_phys.types import BeliefGrid, BoolGrid

OWN = -1  # origin of a cell value the agent sensed itself (255 in a one-byte grid)
NEVER = 0  # the tick of a cell never stamped, and of a pair never synchronised
MAX_BOXES = 96  # per agent; the oldest two are merged beyond this (a superset stays correct)


def origin_type(n: int) -> type[np.integer[Any]]:
    """The dtype of the origins of ``n`` agents' cells: one byte while every index and
    ``OWN`` (stored as 255) fit in it, two bytes beyond (the kernels write ``OWN`` as -1,
    which a byte holds as 255)."""
    return np.uint8 if n <= np.iinfo(np.uint8).max else np.int16


def sensed_tick(step: int) -> int:
    """The tick of what an agent sensed during ``step``."""
    return 2 * step + 1


def received_tick(step: int) -> int:
    """The tick of what an agent received in ``step``'s exchange."""
    return 2 * step + 2


class Ledger:
    """Per-agent change ticks and per-pair sync ticks for n agents on one grid shape."""

    def __init__(self, shape: tuple[int, int], n: int, latest: bool = False) -> None:
        self.latest = latest  # cells carry their observation step; the newer value wins
        self.stamps = [sparse_zeros(shape, np.int32) for _ in range(n)]  # NEVER
        # the newest stamp in each tile of an agent's grid (``deltas.TILE``)
        self.tiles = [np.zeros(tile_shape(shape), dtype=np.int32) for _ in range(n)]
        self.copies = [sparse_zeros(shape, np.uint8) for _ in range(n)]
        self.origins = [sparse_zeros(shape, origin_type(n)) for _ in range(n)]
        self.box_ticks = np.zeros((n, MAX_BOXES + 1), dtype=np.int64)
        self.boxes = np.zeros((n, MAX_BOXES + 1, 4), dtype=np.int64)
        self.box_count = np.zeros(n, dtype=np.int64)
        self.pending: list[Box | None] = [None] * n
        self.synced = np.full((n, n), NEVER, dtype=np.int64)
        self.log: ChangeLog | None = None  # kept for bounded links (:meth:`keep_log`)

    def keep_log(self) -> None:
        """From now on, list every cell each agent changes (:mod:`.changelog`)."""
        if self.log is None:
            shape = self.stamps[0].shape
            self.log = ChangeLog(len(self.stamps), shape[0] * shape[1])

    def note(self, index: int, box: Box) -> None:
        """Agent ``index``'s own map may have changed inside ``box`` (a scan window)."""
        self.pending[index] = union_box(self.pending[index], box)

    def stamp_sensed(self, index: int, belief: BeliefGrid, safe: BoolGrid, step: int) -> None:
        """Give the cells agent ``index`` changed itself since the last call this step's tick."""
        box, self.pending[index] = self.pending[index], None
        if box is None:
            return
        tick = sensed_tick(step)
        grid = (self.copies[index], self.stamps[index], self.tiles[index], self.origins[index])
        out = (
            None
            if self.log is None
            else self.log.room(index, (box[1] - box[0]) * (box[3] - box[2]))
        )
        changed, *tight = stamp_changes(np.array(box, np.int64), belief, safe, *grid, tick, out)
        if self.log is not None:
            self.log.commit(index, tick, changed)
        if changed:
            self.add_box(index, tick, (tight[0], tight[1], tight[2], tight[3]))

    def add_box(self, index: int, tick: int, box: Box) -> None:
        """Remember that agent ``index`` has cells of ``tick`` inside ``box``."""
        k = self.box_count[index]
        self.box_ticks[index, k], self.boxes[index, k] = tick, box
        if k < MAX_BOXES:
            self.box_count[index] = k + 1
            return
        boxes, ticks = self.boxes[index], self.box_ticks[index]
        merged = union_box(tuple(boxes[0].tolist()), tuple(boxes[1].tolist()))
        boxes[1], ticks[1] = merged, ticks[1]
        boxes[:-1], ticks[:-1] = boxes[1:].copy(), ticks[1:].copy()

    def newer_boxes(self, index: int, tick: int) -> np.ndarray:
        """(k, 4) boxes that hold every cell of agent ``index`` stamped after ``tick``."""
        k = self.box_count[index]
        return self.boxes[index, :k][self.box_ticks[index, :k] > tick]

    def merge(
        self,
        index: int,
        cells: Cells,
        grids: tuple[BeliefGrid, BoolGrid],
        step: int,
        sender: int,
        observed: NDArray[np.int32] | None = None,
    ) -> Box | None:
        """Merge received ``cells`` (flat indices, codes[, observation steps]) into agent
        ``index``'s grids (and its ``observed`` steps, with 'latest' beliefs); the box of
        the cells that changed (None: none did)."""
        tick = received_tick(step)
        grid = (self.copies[index], self.stamps[index], self.tiles[index], self.origins[index])
        out = None if self.log is None else self.log.room(index, len(cells.flat))
        changed, *tight = merge_cells(
            cells.flat, cells.codes, cells.seen, *grids, observed, *grid, tick, sender, out
        )
        if self.log is not None:
            self.log.commit(index, tick, changed)
        if not changed:
            return None
        box = (tight[0], tight[1], tight[2], tight[3])
        self.add_box(index, tick, box)
        return box

    def mark_synced(self, members: list[int], tick: int) -> None:
        """Every pair of ``members`` now holds what the other had up to ``tick``."""
        index = np.asarray(members)
        self.synced[np.ix_(index, index)] = tick


def box_around(position: tuple[float, float], radius: float, shape: tuple[int, int]) -> Box:
    """The cells within ``radius`` (a square) of ``position``, clipped to ``shape``."""
    x, y = position
    r0, c0 = max(int(y - radius), 0), max(int(x - radius), 0)
    return r0, min(int(y + radius) + 1, shape[0]), c0, min(int(x + radius) + 1, shape[1])
