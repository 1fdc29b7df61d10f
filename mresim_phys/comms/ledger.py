"""Knowledge ledger (phase 6, bookkeeping): what changed in whose map, and when.

Maps travel as deltas. Every agent's cells carry the *tick* at which they last
changed: tick ``2t`` for what the agent sensed during step ``t``, ``2t + 1`` for
what it received in step ``t``'s exchange. For every ordered pair the ledger keeps
the tick up to which the receiver holds everything the sender had
(``synced[i, j]``), so a transmission carries only the cells whose tick is newer.
Occupancy grids only ever grow (UNKNOWN < FREE < OCCUPIED, safe space only gains
cells), which is why merging deltas ends in exactly the maps a full exchange
gives (tests/test_comms.py checks it step by step).

Changes are found without full-grid passes: the simulation reports the window
of every scan (:meth:`Ledger.note`), and each agent's windows are compared with
the copy taken at its last stamping; a short list of (tick, box) per agent tells a
transmission which part of the grid can hold newer cells.
"""

from __future__ import annotations

import numpy as np

from ..types import BeliefGrid, BoolGrid

Box = tuple[int, int, int, int]  # row0, row1, col0, col1 (half-open)
OWN = -1  # origin of a cell value the agent sensed itself
MAX_BOXES = 24  # per agent; the oldest two are merged beyond this (a superset stays correct)


def union_box(a: Box | None, b: Box | None) -> Box | None:
    """The smallest box holding both (None is empty)."""
    if a is None or b is None:
        return a or b
    return min(a[0], b[0]), max(a[1], b[1]), min(a[2], b[2]), max(a[3], b[3])


def cell_codes(belief: BeliefGrid, safe: BoolGrid) -> np.ndarray:
    """One byte per cell: the occupancy value, plus 4 where the cell is safe space."""
    return belief | (safe.view(np.uint8) << 2)


def sensed_tick(step: int) -> int:
    """The tick of what an agent sensed during ``step``."""
    return 2 * step


def received_tick(step: int) -> int:
    """The tick of what an agent received in ``step``'s exchange."""
    return 2 * step + 1


class Ledger:
    """Per-agent change ticks and per-pair sync ticks for n agents on one grid shape."""

    def __init__(self, shape: tuple[int, int], n: int) -> None:
        self.stamps = [np.full(shape, -1, dtype=np.int32) for _ in range(n)]
        self.copies = [np.zeros(shape, dtype=np.uint8) for _ in range(n)]
        self.origins = [np.full(shape, OWN, dtype=np.int16) for _ in range(n)]
        self.boxes: list[list[tuple[int, Box]]] = [[] for _ in range(n)]
        self.pending: list[Box | None] = [None] * n
        self.synced = np.full((n, n), -1, dtype=np.int64)

    def note(self, index: int, box: Box) -> None:
        """Agent ``index``'s own map may have changed inside ``box`` (a scan window)."""
        self.pending[index] = union_box(self.pending[index], box)

    def stamp_sensed(self, index: int, belief: BeliefGrid, safe: BoolGrid, step: int) -> None:
        """Give the cells agent ``index`` changed itself since the last call this step's tick."""
        box, self.pending[index] = self.pending[index], None
        if box is not None:
            self.stamp(index, box, cell_codes(*window(box, belief, safe)), sensed_tick(step))

    def stamp(self, index: int, box: Box, codes: np.ndarray, tick: int, origin: int = -1) -> int:
        """Stamp the cells of ``box`` whose code differs from the last copy; return how many.

        ``origin`` is the agent the new values came from (-1: the agent's own sensing).
        """
        r0, r1, c0, c1 = box
        copy = self.copies[index][r0:r1, c0:c1]
        changed = codes != copy
        count = int(np.count_nonzero(changed))
        if count:
            self.stamps[index][r0:r1, c0:c1][changed] = tick
            self.origins[index][r0:r1, c0:c1][changed] = origin
            copy[changed] = codes[changed]
            self.add_box(index, tick, box)
        return count

    def add_box(self, index: int, tick: int, box: Box) -> None:
        """Remember that agent ``index`` has cells of ``tick`` inside ``box``."""
        boxes = self.boxes[index]
        if boxes and boxes[-1][0] == tick:
            boxes[-1] = (tick, union_box(boxes[-1][1], box) or box)
        else:
            boxes.append((tick, box))
        if len(boxes) > MAX_BOXES:
            (_, first), (tick2, second) = boxes[0], boxes[1]
            boxes[:2] = [(tick2, union_box(first, second) or first)]

    def newer_box(self, index: int, tick: int) -> Box | None:
        """A box holding every cell of agent ``index`` stamped after ``tick``."""
        box: Box | None = None
        for stamped, part in self.boxes[index]:
            if stamped > tick:
                box = union_box(box, part)
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


def window(box: Box, *grids: np.ndarray) -> list[np.ndarray]:
    """Views of ``grids`` inside ``box``."""
    r0, r1, c0, c1 = box
    return [grid[r0:r1, c0:c1] for grid in grids]
