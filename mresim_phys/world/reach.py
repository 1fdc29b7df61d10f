"""World (phase 1, geometry): the reachable free space, kept up to date as the world changes.

The denominator of the explored metric is the free space 4-connected to the robots'
start points (``maps.free_components_mask``). Labelling the whole map again after
every change costs as much as a third of building the world (800 x 600 office map,
``benchmarks/bench_world.py``), so :class:`Reachable` relabels only a window: the
flipped cells' bounding box grown by :data:`MARGIN`. Outside the window nothing
changed, so connectivity between cells outside it can only change through it: paths
enter and leave the window through its *ring* (its cells with a neighbour outside
it). If the window connects its free ring cells (and any seed inside it) into the
same groups before and after the change, reachability outside the window is as
before, and a window cell is reachable exactly when its component in the window
holds a reachable ring cell or a seed. Otherwise (a door closed or opened, a seed
was covered) the whole map is labelled again. ``tests/test_reach.py`` checks the
result against a full labelling on random change sequences.

Seeds that a change buried stop seeding (and seed again once uncovered); at
construction a blocked seed is an error, as for ``free_components_mask``.
:func:`follow_changes` is the one call the simulation makes after changes: bring the
reachable set up to date and retarget the coverage counter to it.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

import numpy as np
from numba import njit
from numpy.typing import ArrayLike

from mresim_phys.types import BoolGrid, IntArray
from mresim_phys.world.changes import Change, Patch, union_box
from mresim_phys.world.maps import (
    connected_to,
    free_components_mask,
    seed_cells,
)
from mresim_phys.world.wallset import Box

MARGIN = 2  # cells around the flipped cells relabelled locally
LOCAL_SHARE = 0.25  # a window larger than this share of the map: relabel the whole map
NOTHING: Box = (0, 0, 0, 0)


class Retargets(Protocol):
    """Anything that counts against a reachable set (``knowledge.coverage.Coverage``)."""

    def retarget(
        self, reachable: BoolGrid, window: Box | None = None, before: BoolGrid | None = None
    ) -> None:
        """Count against ``reachable`` from now on (it differs only inside ``window``,
        where it held ``before`` if it was changed in place)."""
        ...


class Reachable:
    """The free cells 4-connected to fixed seed points, followed across changes."""

    def __init__(self, occupied: BoolGrid, seeds_xy: ArrayLike) -> None:
        self.mask = free_components_mask(occupied, seeds_xy)
        self.seeds = seed_cells(seeds_xy, occupied.shape)
        self.relabels = 0  # how often a change needed the whole map labelled again

    def follow(self, occupied: BoolGrid, changes: Sequence[Change]) -> tuple[Box, BoolGrid | None]:
        """Bring :attr:`mask` up to date with ``changes`` (every change since the last call,
        ``occupied`` the truth after them); return the box outside which it did not change
        and what the mask held there before (None when the whole map was labelled again).

        A local change writes :attr:`mask` in place; labelling the whole map again makes
        it a new array, leaving the previous one as it was.
        """
        patches = [patch for change in changes for patch in change.patches]
        if not patches:
            return NOTHING, None
        window = grown(union_box(patches), MARGIN, occupied.shape)
        local = None
        if area(window) <= LOCAL_SHARE * occupied.size:
            local = self._local(occupied, patches, window)
        if local is None:
            self.relabels += 1
            free = ~occupied
            self.mask = connected_to(free, self.seeds)
            return (0, occupied.shape[0], 0, occupied.shape[1]), None
        region = self.mask[window[0] : window[1], window[2] : window[3]]
        before = region.copy()
        region[...] = local
        return window, before

    def _local(self, occupied: BoolGrid, patches: list[Patch], window: Box) -> BoolGrid | None:
        """The reachable cells of ``window`` after the change, or None if the change may
        have changed connectivity beyond the window."""
        row0, row1, col0, col1 = window
        free = ~occupied[row0:row1, col0:col1]
        was_free = free ^ flips_in(patches, window)
        ring = ring_of(window, occupied.shape)
        local = np.zeros(free.shape, dtype=bool)
        seeds = (self.seeds - np.array([row0, col0])).astype(np.int64)
        reached = self.mask[row0:row1, col0:col1]
        if not relabel_window(free, was_free, ring, seeds, reached, local):
            return None
        return local


@njit(cache=True, nogil=True)
def _label(free: BoolGrid, labels: IntArray) -> int:
    """4-connected components of ``free`` into ``labels`` (0: not free); returns their count."""
    rows, cols = free.shape
    stack = np.empty(rows * cols, dtype=np.int64)
    count = 0
    for start in range(rows * cols):
        r0, c0 = divmod(start, cols)
        if not free[r0, c0] or labels[r0, c0]:
            continue
        count += 1
        labels[r0, c0], stack[0], top = count, start, 1
        while top:
            top -= 1
            r, c = divmod(stack[top], cols)
            for dr, dc in ((-1, 0), (1, 0), (0, -1), (0, 1)):
                rr, cc = r + dr, c + dc
                if 0 <= rr < rows and 0 <= cc < cols and free[rr, cc] and not labels[rr, cc]:
                    labels[rr, cc] = count
                    stack[top] = rr * cols + cc
                    top += 1
    return count


@njit(cache=True, nogil=True)
def relabel_window(
    free: BoolGrid, was_free: BoolGrid, ring: BoolGrid, seeds: IntArray, reached: BoolGrid,
    out: BoolGrid,
) -> bool:  # fmt: skip
    """Reachability inside a window after a change, from its ring and seeds (see the module
    docstring): ``free`` / ``was_free`` the window after / before, ``ring`` the cells with a
    neighbour outside it, ``seeds`` (window coordinates; outside ones are skipped),
    ``reached`` the reachable set before. Writes ``out`` and returns True, or returns False
    when a seed flipped or the change regrouped the terminals (free ring cells and seeds)."""
    rows, cols = free.shape
    terminal = ring & free
    for k in range(len(seeds)):
        r, c = seeds[k, 0], seeds[k, 1]
        if 0 <= r < rows and 0 <= c < cols:
            if not (free[r, c] and was_free[r, c]):
                return False
            terminal[r, c] = True
    before, after = np.zeros((rows, cols), np.int64), np.zeros((rows, cols), np.int64)
    n_before, n_after = _label(was_free, before), _label(free, after)
    to_after = np.full(n_before + 1, -1, np.int64)
    to_before = np.full(n_after + 1, -1, np.int64)
    keep = np.zeros(n_after + 1, dtype=np.bool_)
    for r in range(rows):
        for c in range(cols):
            if not terminal[r, c]:
                continue
            b, a = before[r, c], after[r, c]
            if to_after[b] == -1 and to_before[a] == -1:
                to_after[b], to_before[a] = a, b
            elif to_after[b] != a or to_before[a] != b:
                return False
            keep[a] |= reached[r, c]  # a seed was free before: it was reached
    for r in range(rows):
        for c in range(cols):
            out[r, c] = keep[after[r, c]] and after[r, c] > 0
    return True


def follow_changes(
    coverage: Retargets, reachable: Reachable, occupied: BoolGrid, changes: Sequence[Change]
) -> None:
    """After ``changes`` of the world: update the reachable set, retarget ``coverage`` to it."""
    window, before = reachable.follow(occupied, changes)
    if window != NOTHING:
        coverage.retarget(reachable.mask, window, before)


def grown(box: Box, margin: int, shape: tuple[int, int]) -> Box:
    """``box`` grown by ``margin`` cells on every side, clipped to a map of ``shape``."""
    row0, row1, col0, col1 = box
    rows, cols = shape
    return (
        max(row0 - margin, 0),
        min(row1 + margin, rows),
        max(col0 - margin, 0),
        min(col1 + margin, cols),
    )


def area(box: Box) -> int:
    """Number of cells of ``box``."""
    return (box[1] - box[0]) * (box[3] - box[2])


def flips_in(patches: Sequence[Patch], window: Box) -> BoolGrid:
    """Cells of ``window`` flipped an odd number of times by ``patches`` (so before ^ after)."""
    row0, row1, col0, col1 = window
    flips = np.zeros((row1 - row0, col1 - col0), dtype=bool)
    for patch in patches:
        r0, r1, c0, c1 = patch.box
        flips[r0 - row0 : r1 - row0, c0 - col0 : c1 - col0] ^= patch.flipped
    return flips


def ring_of(window: Box, shape: tuple[int, int]) -> BoolGrid:
    """Cells of ``window`` with a 4-neighbour outside it but inside a map of ``shape``."""
    row0, row1, col0, col1 = window
    ring = np.zeros((row1 - row0, col1 - col0), dtype=bool)
    ring[0, :] |= row0 > 0
    ring[-1, :] |= row1 < shape[0]
    ring[:, 0] |= col0 > 0
    ring[:, -1] |= col1 < shape[1]
    return ring
