"""Change logs and send order on bounded links (``comms/changelog.py``, ``comms/send_order.py``):
the log lists exactly the cells stamped after a tick, a selection over it picks what a scan
of the boxes picks, and a packet's cut takes the cells first in priority order."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from mresim_phys.comms.changelog import ChangeLog, PairGrids, as_row, select_listed, still_news
from mresim_phys.comms.deltas import Cells, select_cells
from mresim_phys.comms.ledger import NEVER, Ledger
from mresim_phys.comms.send_order import NO_TIER, cut_nearest
from mresim_phys.types import FREE, OCCUPIED

SHAPE = (30, 40)


def random_merges(ledger: Ledger, rng: np.random.Generator, steps: int) -> None:
    """Agent 0 senses patches and merges packets from agents 1 and 2, step by step."""
    belief = np.zeros(SHAPE, np.uint8)
    safe = np.zeros(SHAPE, bool)
    for step in range(steps):
        r, c = int(rng.integers(0, SHAPE[0] - 5)), int(rng.integers(0, SHAPE[1] - 5))
        belief[r : r + 5, c : c + 5] = np.maximum(belief[r : r + 5, c : c + 5], FREE)
        ledger.note(0, (r, r + 5, c, c + 5))
        ledger.stamp_sensed(0, belief, safe, step)
        for sender in (1, 2):
            flat = rng.choice(SHAPE[0] * SHAPE[1], size=40, replace=False).astype(np.int64)
            codes = rng.choice([FREE, OCCUPIED, FREE | 4], size=40).astype(np.uint8)
            ledger.merge(0, Cells(flat, codes), (belief, safe), step, sender)


@given(seed=st.integers(0, 2**32 - 1), since=st.integers(NEVER, 31))
@settings(max_examples=40, deadline=None)
def test_the_log_lists_exactly_the_cells_stamped_after_a_tick(seed: int, since: int) -> None:
    rng = np.random.default_rng(seed)
    ledger = Ledger(SHAPE, 3)
    ledger.keep_log()
    random_merges(ledger, rng, 15)
    assert ledger.log is not None
    listed = ledger.log.newer(0, since)
    assert listed is not None
    stamped = set(np.flatnonzero(ledger.stamps[0].reshape(-1) > since).tolist())
    assert set(listed.tolist()) == stamped


def test_a_log_past_its_limit_forgets_its_oldest_runs_and_says_so() -> None:
    log = ChangeLog(1, 100)
    log.limit = 10
    for tick in range(6):
        room = log.room(0, 3)
        room[:] = [tick, tick + 100, tick + 200]
        log.commit(0, tick, 3)
    assert log.size[0] <= log.limit
    assert log.newer(0, -1) is None  # entries that old are gone: the caller scans instead
    newest = log.newer(0, 4)
    assert newest is not None and newest.tolist() == [5, 105, 205]
    kept = log.newer(0, log.dropped[0])
    assert kept is not None and len(kept) == log.size[0]


@given(seed=st.integers(0, 2**32 - 1), since=st.integers(-1, 30), receiver=st.integers(1, 3))
@settings(max_examples=40, deadline=None)
def test_a_selection_over_the_log_picks_what_a_scan_of_the_boxes_picks(
    seed: int, since: int, receiver: int
) -> None:
    rng = np.random.default_rng(seed)
    ledger = Ledger(SHAPE, 4)
    ledger.keep_log()
    random_merges(ledger, rng, 15)
    theirs = np.where(
        rng.random(SHAPE) < 0.5, ledger.copies[0], rng.integers(0, 8, size=SHAPE)
    ).astype(np.uint8)
    grids = PairGrids(ledger.stamps[0], ledger.origins[0], ledger.copies[0], theirs, None, None)
    rows = grids.rows()
    assert ledger.log is not None
    listed = ledger.log.newer(0, since)
    assert listed is not None
    marks, mark = ledger.log.next_mark(SHAPE)
    index, values = select_listed(listed, receiver, as_row(marks), mark, *rows[1:])
    boxes = ledger.newer_boxes(0, since)
    expected, codes = select_cells(
        boxes, since, receiver, ledger.stamps[0], ledger.tiles[0], ledger.origins[0],
        ledger.copies[0], theirs, False, True,
    )  # fmt: skip
    assert sorted(index.tolist()) == sorted(expected.tolist())
    assert dict(zip(index.tolist(), values.tolist(), strict=True)) == dict(
        zip(expected.tolist(), codes.tolist(), strict=True)
    )


def test_a_queued_cell_stamped_since_is_left_to_the_new_ones() -> None:
    stamps = np.zeros(SHAPE, np.int32)
    stamps[0, 1] = 9
    codes = np.full(SHAPE, FREE, np.uint8)
    grids = PairGrids(
        stamps, np.full(SHAPE, -1, np.int16), codes, np.zeros(SHAPE, np.uint8), None, None
    )
    index, _ = still_news(np.array([0, 1, 2], np.int64), 1, 5, *grids.rows())
    assert index.tolist() == [0, 2]


@given(
    seed=st.integers(0, 2**32 - 1),
    count=st.integers(1, 60),
    tiered=st.booleans(),
)
@settings(max_examples=60, deadline=None)
def test_a_cut_takes_the_cells_first_in_priority_order(seed: int, count: int, tiered: bool) -> None:
    """Every cell taken comes before (or ties with) every cell left: the later tier after
    the rest, then by distance from the point."""
    rng = np.random.default_rng(seed)
    cols = SHAPE[1]
    index = rng.choice(SHAPE[0] * cols, size=50, replace=False).astype(np.int64)
    stamps = rng.integers(0, 10, size=SHAPE[0] * cols).astype(np.int32)
    x, y = rng.uniform(-5, 45), rng.uniform(-5, 35)
    upto = 4 if tiered else NO_TIER
    taken = cut_nearest(index, cols, x, y, count, stamps, upto)
    assert len(taken) == min(count, len(index)) and len(set(taken.tolist())) == len(taken)
    later = stamps[index] <= upto
    squared = (index % cols + 0.5 - x) ** 2 + (index // cols + 0.5 - y) ** 2
    key = list(zip(later.tolist(), squared.tolist(), strict=True))
    left = np.setdiff1d(np.arange(len(index)), taken)
    if len(left):
        assert max(key[k] for k in taken) <= min(key[k] for k in left)
