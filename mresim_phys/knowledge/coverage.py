"""Metrics (phase 7): the explored count, from the windows robots' maps changed in a step.

:class:`Coverage` counts the explorable cells (``world.explorable``) that some robot's map
has held FREE, and, when given the free cells 4-connected to the starts (``world.reach``,
the definition before the explorable area), those too: ``explored_connected``. A step's
scans report their windows and only those are examined at the end of the step. (A compiled
pass over each window measured no faster than the numpy masks: ~34 against ~29 us a robot
at the original's settings, the windows being mostly cells already known.)
"""

from __future__ import annotations

import numpy as np

from mresim_phys.knowledge.mapping import Update
from mresim_phys.types import FREE, BeliefGrid, BoolGrid


class Coverage:
    """Counted cells that some robot's map held as FREE at the end of a step.

    The numerator of ``explored``: ``reachable`` holds the cells counted (the explorable
    area); ``connected``, if given, a second set counted alongside (``count_connected``
    of ``total_connected``: ``explored_connected``). Scans report the windows they
    touched (:meth:`touch`); at the end of the step only those windows are examined
    (:meth:`settle`), so the metric never needs a full-grid pass and never
    decreases while the world stays as it is. A run log's map deltas give exactly
    the same count on replay. When the world changes, :meth:`retarget` and
    :meth:`retarget_connected` (called by ``world.explorable.follow_world``) count
    against the new sets: cells walled off leave both the count and the total, newly
    opened ones join the total.
    """

    def __init__(self, reachable: BoolGrid, connected: BoolGrid | None = None) -> None:
        self.reachable = reachable
        self.total = int(reachable.sum())
        self.known = np.zeros_like(reachable)  # every cell some robot has held FREE
        self.count = 0
        self.connected = connected
        self.total_connected = 0 if connected is None else int(connected.sum())
        self.count_connected = 0
        self._pending: list[tuple[BeliefGrid, int, int, int, int]] = []

    def retarget(
        self,
        reachable: BoolGrid,
        window: tuple[int, int, int, int] | None = None,
        before: BoolGrid | None = None,
    ) -> None:
        """The world changed: count against the new set ``reachable`` from now on.

        Cells already held FREE and still counted keep counting; cells that left the
        set stop counting; cells new to it count once seen FREE. ``window`` (row0, row1,
        col0, col1), if given, is where ``reachable`` may differ from the set counted so
        far: only that window is recounted. ``before`` is what the set held in the
        window, if ``reachable`` is that set changed in place.
        """
        self.total, self.count = recount(
            self.known, self.reachable, reachable, window, before, (self.total, self.count)
        )
        self.reachable = reachable

    def retarget_connected(
        self,
        connected: BoolGrid,
        window: tuple[int, int, int, int] | None = None,
        before: BoolGrid | None = None,
    ) -> None:
        """:meth:`retarget` for the second set (a coverage without one ignores it)."""
        if self.connected is None:
            return
        totals = (self.total_connected, self.count_connected)
        totals = recount(self.known, self.connected, connected, window, before, totals)
        self.total_connected, self.count_connected = totals
        self.connected = connected

    def touch(self, belief: BeliefGrid, update: Update) -> None:
        """Remember that ``update``'s window of ``belief`` changed this step."""
        h, w = update.free.shape
        self.touch_box(belief, (update.row0, update.row0 + h, update.col0, update.col0 + w))

    def touch_box(self, belief: BeliefGrid, box: tuple[int, int, int, int]) -> None:
        """Remember that ``belief`` may have changed inside ``box`` (row0, row1, col0, col1)
        this step."""
        self._pending.append((belief, *box))

    def settle(self) -> None:
        """Count the reachable cells now FREE in the touched windows, not counted before.

        The windows of one belief are examined as their union box (a robot's scans of
        one step overlap almost entirely): a cell of the box outside every window did
        not change in that belief by a scan, and a cell a merge made FREE was counted
        when the robot that scanned it touched it, so the count is the same."""
        boxes: dict[int, tuple[BeliefGrid, int, int, int, int]] = {}
        for belief, r0, r1, c0, c1 in self._pending:
            held = boxes.get(id(belief))
            if held is not None:
                r0, r1 = min(r0, held[1]), max(r1, held[2])
                c0, c1 = min(c0, held[3]), max(c1, held[4])
            boxes[id(belief)] = (belief, r0, r1, c0, c1)
        for belief, r0, r1, c0, c1 in boxes.values():
            self.add_cells(belief[r0:r1, c0:c1] == FREE, r0, c0)
        self._pending.clear()

    def add_cells(self, free: BoolGrid, row0: int, col0: int) -> None:
        """Count the reachable cells of ``free`` (a window at row0, col0) not seen before."""
        h, w = free.shape
        seen = self.known[row0 : row0 + h, col0 : col0 + w]
        new = free & ~seen
        self.count += int(np.count_nonzero(new & self.reachable[row0 : row0 + h, col0 : col0 + w]))
        if self.connected is not None:
            connected = self.connected[row0 : row0 + h, col0 : col0 + w]
            self.count_connected += int(np.count_nonzero(new & connected))
        seen |= new

    @property
    def fraction(self) -> float:
        """Known counted cells / all counted cells (``explored``)."""
        return self.count / self.total if self.total else 1.0

    @property
    def fraction_connected(self) -> float | None:
        """The same over the second set (``explored_connected``); None without one."""
        if self.connected is None:
            return None
        return self.count_connected / self.total_connected if self.total_connected else 1.0


def recount(
    known: BoolGrid,
    old_set: BoolGrid,
    new_set: BoolGrid,
    window: tuple[int, int, int, int] | None,
    before: BoolGrid | None,
    totals: tuple[int, int],
) -> tuple[int, int]:
    """(total, count) of the cells of ``new_set`` (and of those ``known``) given those of
    ``old_set``: over the whole grid, or only ``window`` (where ``old_set`` held
    ``before`` if ``new_set`` is it changed in place)."""
    if window is None:
        return int(np.count_nonzero(new_set)), int(np.count_nonzero(known & new_set))
    r0, r1, c0, c1 = window
    old = old_set[r0:r1, c0:c1] if before is None else before
    new = new_set[r0:r1, c0:c1]
    inside = known[r0:r1, c0:c1]
    total = totals[0] + int(np.count_nonzero(new)) - int(np.count_nonzero(old))
    count = totals[1] + int(np.count_nonzero(inside & new)) - int(np.count_nonzero(inside & old))
    return total, count
