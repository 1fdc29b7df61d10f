"""The cell-merge kernel: one loop, the 'grow' and the 'latest' rule per cell."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import pytest

from mresim_phys.comms.deltas import merge_cells, tile_shape
from mresim_phys.types import FREE, OCCUPIED, UNKNOWN

SAFE = 4  # the safe-space bit of a cell code
SENDER, TICK = 3, 11


class Receiver(NamedTuple):
    """One receiver's grids, as :meth:`Ledger.merge` hands them to the kernel."""

    belief: np.ndarray
    safe: np.ndarray
    observed: np.ndarray
    codes: np.ndarray
    stamps: np.ndarray
    tiles: np.ndarray
    origins: np.ndarray


def receiver(codes: list[int], observed: list[int] | None = None) -> Receiver:
    """A one-row receiver holding ``codes`` (observed at ``observed``, 'latest' beliefs)."""
    shape = (1, len(codes))
    code = np.array([codes], np.uint8)
    steps = np.array([observed if observed is not None else [-1] * len(codes)], np.int32)
    return Receiver(
        code & 3,
        (code & SAFE) != 0,
        steps,
        code.copy(),
        np.full(shape, -1, np.int32),
        np.full(tile_shape(shape), -1, np.int32),
        np.full(shape, -1, np.int16),
    )


def merge(mine: Receiver, theirs: list[int], seen: list[int] | None = None) -> tuple[int, ...]:
    """Merge ``theirs`` (one code per cell of the row; with ``seen``, 'latest' beliefs)."""
    index = np.arange(len(theirs), dtype=np.int64)
    values = np.array(theirs, np.uint8)
    steps = None if seen is None else np.array(seen, np.int32)
    observed = None if seen is None else mine.observed
    grids = (mine.codes, mine.stamps, mine.tiles, mine.origins)
    result = merge_cells(
        index, values, steps, mine.belief, mine.safe, observed, *grids, TICK, SENDER
    )
    return tuple(int(v) for v in result)


@pytest.mark.parametrize(
    ("mine", "theirs", "merged", "origin"),
    [
        (UNKNOWN, FREE, FREE, SENDER),  # the larger occupancy, exactly the sender's
        (OCCUPIED, FREE, OCCUPIED, -1),  # the receiver's own value stays, unstamped
        (FREE, FREE | SAFE, FREE | SAFE, SENDER),  # safe space is OR-ed
        (OCCUPIED, FREE | SAFE, OCCUPIED | SAFE, -1),  # mixed from both sides: its own
        (OCCUPIED | SAFE, UNKNOWN, OCCUPIED | SAFE, -1),
    ],
)
def test_grow_takes_the_larger_occupancy_and_ors_safe_space(
    mine: int, theirs: int, merged: int, origin: int
) -> None:
    cells = receiver([mine])
    changed = int(merged != mine)
    assert merge(cells, [theirs])[0] == changed
    assert int(cells.codes[0, 0]) == merged
    assert int(cells.belief[0, 0]) == merged & 3 and bool(cells.safe[0, 0]) == bool(merged & 4)
    assert int(cells.origins[0, 0]) == origin
    assert int(cells.stamps[0, 0]) == (TICK if changed else -1)
    assert int(cells.tiles[0, 0]) == (TICK if changed else -1)


@pytest.mark.parametrize(
    ("mine", "theirs", "merged", "origin"),
    [
        ((OCCUPIED, 5), (FREE, 9), (FREE, 9), SENDER),  # the newer observation wins
        ((FREE, 9), (OCCUPIED, 5), (FREE, 9), -1),  # the older one loses
        ((FREE, 7), (OCCUPIED, 7), (OCCUPIED, 7), SENDER),  # the same step: the obstacle
        ((OCCUPIED, 7), (FREE, 7), (OCCUPIED, 7), -1),
        ((UNKNOWN, -1), (FREE, 3), (FREE, 3), SENDER),
        ((FREE | SAFE, 5), (OCCUPIED, 9), (OCCUPIED | SAFE, 9), -1),  # mixed: its own
        ((OCCUPIED, 9), (FREE | SAFE, 5), (OCCUPIED | SAFE, 9), -1),  # an older safe flag
    ],
)
def test_latest_keeps_the_newer_observation(
    mine: tuple[int, int], theirs: tuple[int, int], merged: tuple[int, int], origin: int
) -> None:
    cells = receiver([mine[0]], [mine[1]])
    changed = int(merged[0] != mine[0])
    assert merge(cells, [theirs[0]], [theirs[1]])[0] == changed
    assert (int(cells.codes[0, 0]), int(cells.observed[0, 0])) == merged
    assert int(cells.belief[0, 0]) == merged[0] & 3
    assert bool(cells.safe[0, 0]) == bool(merged[0] & 4)
    assert int(cells.origins[0, 0]) == origin
    assert int(cells.stamps[0, 0]) == (TICK if changed else -1)


def test_a_newer_observation_of_an_equal_value_only_moves_its_step() -> None:
    cells = receiver([FREE], [4])
    assert merge(cells, [FREE], [8])[0] == 0
    assert int(cells.observed[0, 0]) == 8 and int(cells.stamps[0, 0]) == -1


def test_the_same_codes_merge_as_grow_or_as_latest() -> None:
    mine, theirs = [UNKNOWN, OCCUPIED, FREE, FREE], [FREE, FREE, OCCUPIED, FREE | SAFE]
    grow, latest = receiver(mine), receiver(mine, [2, 2, 2, 2])
    assert merge(grow, theirs) == (3, 0, 1, 0, 4)
    assert [int(v) for v in grow.codes[0]] == [FREE, OCCUPIED, OCCUPIED, FREE | SAFE]
    assert merge(latest, theirs, [3, 3, 1, 3]) == (3, 0, 1, 0, 4)
    assert [int(v) for v in latest.codes[0]] == [FREE, FREE, FREE, FREE | SAFE]
    assert [int(v) for v in latest.observed[0]] == [3, 3, 2, 3]


def test_observation_steps_on_one_side_only_merge_as_grow() -> None:
    theirs, seen = np.array([FREE], np.uint8), np.array([9], np.int32)
    for steps, observed in ((seen, None), (None, np.array([[5]], np.int32))):
        cells = receiver([OCCUPIED], [5])
        grids = (cells.codes, cells.stamps, cells.tiles, cells.origins)
        index = np.zeros(1, np.int64)
        merge_cells(index, theirs, steps, cells.belief, cells.safe, observed, *grids, TICK, SENDER)
        assert int(cells.codes[0, 0]) == OCCUPIED and int(cells.observed[0, 0]) == 5


def reference(mine: Receiver, theirs: np.ndarray, seen: np.ndarray | None) -> None:
    """The merge rule cell by cell in plain Python ('latest' beliefs with ``seen``)."""
    for c, value in enumerate(theirs.tolist()):
        old = int(mine.codes[0, c])
        occupancy = max(old & 3, value & 3)
        if seen is not None:
            own = int(mine.observed[0, c])
            if seen[c] > own:
                occupancy, mine.observed[0, c] = value & 3, seen[c]
            elif seen[c] < own:
                occupancy = old & 3
        new = occupancy | ((old | value) & 4)
        if new != old:
            mine.codes[0, c], mine.belief[0, c], mine.safe[0, c] = new, new & 3, new >= 4
            mine.stamps[0, c], mine.origins[0, c] = TICK, SENDER if new == value else -1
            mine.tiles[0, c // 16] = TICK


@pytest.mark.parametrize("latest", [False, True])
def test_the_kernel_matches_the_rule_cell_by_cell(latest: bool) -> None:
    rng = np.random.default_rng(30)
    codes = [int(v) for v in rng.choice([0, 1, 2, 5, 6], 200)]
    steps = [int(v) for v in rng.integers(-1, 6, 200)] if latest else None
    theirs = rng.choice([0, 1, 2, 5, 6], 200).astype(np.uint8)
    seen = rng.integers(0, 6, 200).astype(np.int32) if latest else None
    kernel, expected = receiver(codes, steps), receiver(codes, steps)
    merge(kernel, theirs.tolist(), None if seen is None else seen.tolist())
    reference(expected, theirs, seen)
    for got, want in zip(kernel, expected, strict=True):
        np.testing.assert_array_equal(got, want)
