"""Change logs (phase 6b, bookkeeping): the exact cells each agent changed, tick by tick.

On bounded links each pair's queue asks, every step it is linked, for the sender's cells
stamped since the queue last looked (``comms/offers.py``). The ledger's boxes answer with
every cell of a few windows; on a team of 32 a sender's boxes span the merges from all over
the map, so a selection visited about twice the cells that had changed, most of them in
tiles where a few had. A change log lists, in the order they were stamped, the flat index
of every cell an agent's sensing or merges changed, with the tick at which each run of
entries starts; the cells stamped after a tick are a suffix of it. It keeps at most
``limit`` entries: the oldest runs are dropped, and a question about ticks older than what
was dropped has no answer here (the caller scans the boxes instead).
"""

from __future__ import annotations

from bisect import bisect_right
from typing import NamedTuple

import numpy as np
from numba import njit

from mresim_phys.comms.deltas import is_news
from mresim_phys.types import IntArray

MIN_LIMIT = 1 << 16  # entries an agent's log keeps at least


class ChangeLog:
    """Per agent: flat cells in stamping order, and the tick at which each run starts."""

    def __init__(self, n: int, cells: int) -> None:
        self.limit = max(MIN_LIMIT, cells // 4)
        self.entries = [np.empty(1024, dtype=np.int64) for _ in range(n)]
        self.size = [0] * n
        self.ticks: list[list[int]] = [[] for _ in range(n)]  # the tick of each run
        self.starts: list[list[int]] = [[] for _ in range(n)]  # where each run starts
        self.dropped = [-1] * n  # the newest tick of an entry no longer kept
        self.marks: np.ndarray | None = None  # a scratch grid for the selection's dedup
        self.mark = 0

    def room(self, index: int, count: int) -> IntArray:
        """A view with room for ``count`` entries after agent ``index``'s last: the caller
        writes into it, then calls :meth:`commit`."""
        size, buffer = self.size[index], self.entries[index]
        if size + count > len(buffer):
            grown = np.empty(max(2 * len(buffer), size + count), dtype=np.int64)
            grown[:size] = buffer[:size]
            self.entries[index] = buffer = grown
        return buffer[size : size + count]

    def commit(self, index: int, tick: int, count: int) -> None:
        """Agent ``index``'s next ``count`` entries (written through :meth:`room`) were
        stamped ``tick`` (no older than any before)."""
        if count == 0:
            return
        ticks = self.ticks[index]
        if not ticks or ticks[-1] != tick:
            ticks.append(tick)
            self.starts[index].append(self.size[index])
        self.size[index] += count
        if self.size[index] > self.limit:
            self.forget(index)

    def forget(self, index: int) -> None:
        """Drop agent ``index``'s oldest runs until at most half the limit is kept."""
        ticks, starts, size = self.ticks[index], self.starts[index], self.size[index]
        cut = 1
        while cut < len(ticks) and size - starts[cut] > self.limit // 2:
            cut += 1
        first = starts[cut] if cut < len(ticks) else size
        self.dropped[index] = ticks[cut - 1]
        buffer = self.entries[index]
        buffer[: size - first] = buffer[first:size].copy()
        self.ticks[index] = ticks[cut:]
        self.starts[index] = [s - first for s in starts[cut:]]
        self.size[index] = size - first

    def newer(self, index: int, tick: int) -> IntArray | None:
        """Every cell agent ``index`` stamped after ``tick`` (some more than once), or None
        when entries that old are no longer kept."""
        if tick < self.dropped[index]:
            return None
        run = bisect_right(self.ticks[index], tick)
        start = self.starts[index][run] if run < len(self.ticks[index]) else self.size[index]
        return self.entries[index][start : self.size[index]]

    def next_mark(self, shape: tuple[int, int]) -> tuple[np.ndarray, int]:
        """The scratch grid and a mark no cell of it holds yet."""
        if self.marks is None or self.mark == np.iinfo(np.int32).max:
            self.marks, self.mark = np.zeros(shape, dtype=np.int32), 0
        self.mark += 1
        return self.marks, self.mark


@njit(cache=True, nogil=True)
def select_listed(
    listed: IntArray,
    receiver: int,
    marks: np.ndarray,
    mark: int,
    origins: np.ndarray,
    codes: np.ndarray,
    receiver_codes: np.ndarray,
    seen: np.ndarray | None = None,
    observed: np.ndarray | None = None,
) -> tuple[IntArray, np.ndarray]:
    """(flat indices, codes) of the cells ``listed`` (a log's suffix), each once (``marks``
    set to ``mark`` where taken), whose value did not come from ``receiver`` and that are
    news to it (:func:`~.deltas.is_news`): the selection of ``deltas.select_cells`` with
    ``news``, over exactly the cells that changed. Most listed cells are no news (the
    receiver has them), so that is checked first, and only a cell taken is marked. Every
    grid comes as one row (:func:`as_row`): a flat index is its column, with no division."""
    index = np.empty(len(listed), np.int64)
    values = np.empty(len(listed), np.uint8)
    n = 0
    for k in range(len(listed)):
        c = listed[k]
        if not is_news(codes, receiver_codes, seen, observed, 0, c):
            continue
        if origins[0, c] == receiver or marks[0, c] == mark:
            continue
        marks[0, c] = mark
        index[n] = c
        values[n] = codes[0, c]
        n += 1
    return index[:n], values[:n]


@njit(cache=True, nogil=True)
def still_news(
    flat: IntArray,
    receiver: int,
    since: int,
    stamps: np.ndarray,
    origins: np.ndarray,
    codes: np.ndarray,
    receiver_codes: np.ndarray,
    seen: np.ndarray | None = None,
    observed: np.ndarray | None = None,
) -> tuple[IntArray, np.ndarray]:
    """(flat indices, codes) of the cells ``flat`` of a sender (a queue's remainder) that
    are still news to ``receiver`` (:func:`~.deltas.is_news`), whose value did not come
    from it and that are stamped no later than ``since`` (a cell stamped since is found
    again among the new ones, so none is offered twice). Grids as rows (:func:`as_row`)."""
    index = np.empty(len(flat), np.int64)
    values = np.empty(len(flat), np.uint8)
    n = 0
    for k in range(len(flat)):
        c = flat[k]
        if stamps[0, c] > since or origins[0, c] == receiver:
            continue
        if not is_news(codes, receiver_codes, seen, observed, 0, c):
            continue
        index[n] = c
        values[n] = codes[0, c]
        n += 1
    return index[:n], values[:n]


def as_row(grid: np.ndarray) -> np.ndarray:
    """``grid`` (C-contiguous) viewed as a single row: a flat index is its column."""
    return grid.reshape(1, -1)


class PairGrids(NamedTuple):
    """The grids a selection for one ordered pair reads: the sender's stamps, origins and
    codes, the receiver's codes, and with 'latest' beliefs both observation steps."""

    stamps: np.ndarray
    origins: np.ndarray
    codes: np.ndarray
    receiver_codes: np.ndarray
    seen: np.ndarray | None
    observed: np.ndarray | None

    def rows(self) -> PairGrids:
        """The same grids, each as one row (:func:`as_row`)."""
        seen, observed = self.seen, self.observed
        return PairGrids(
            as_row(self.stamps), as_row(self.origins), as_row(self.codes),
            as_row(self.receiver_codes), None if seen is None else as_row(seen),
            None if observed is None else as_row(observed),
        )  # fmt: skip
