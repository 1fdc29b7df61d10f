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
from numpy.typing import ArrayLike
from scipy import ndimage

from mresim_phys.types import BoolGrid, IntArray
from mresim_phys.world.changes import Change, Patch, union_box
from mresim_phys.world.maps import (
    FOUR_CONNECTED,
    connected_to,
    free_components_mask,
    seed_cells,
)
from mresim_phys.world.wallset import Box

MARGIN = 2  # cells around the flipped cells relabelled locally
LOCAL_SHARE = 0.25  # a window larger than this share of the map: relabel the whole map
NOTHING: Box = (0, 0, 0, 0)


class Retargets(Protocol):
    """Anything that counts against a reachable set (``knowledge.mapping.Coverage``)."""

    def retarget(self, reachable: BoolGrid, window: Box | None = None) -> None:
        """Count against ``reachable`` from now on (it differs only inside ``window``)."""
        ...


class Reachable:
    """The free cells 4-connected to fixed seed points, followed across changes."""

    def __init__(self, occupied: BoolGrid, seeds_xy: ArrayLike) -> None:
        self.mask = free_components_mask(occupied, seeds_xy)
        self.seeds = seed_cells(seeds_xy, occupied.shape)
        self.relabels = 0  # how often a change needed the whole map labelled again

    def follow(self, occupied: BoolGrid, changes: Sequence[Change]) -> Box:
        """Bring :attr:`mask` up to date with ``changes`` (every change since the last call,
        ``occupied`` the truth after them); return the box outside which it did not change.

        :attr:`mask` becomes a new array; the previous one is left as it was.
        """
        patches = [patch for change in changes for patch in change.patches]
        if not patches:
            return NOTHING
        window = grown(union_box(patches), MARGIN, occupied.shape)
        local = None
        if area(window) <= LOCAL_SHARE * occupied.size:
            local = self._local(occupied, patches, window)
        if local is None:
            self.relabels += 1
            free = ~occupied
            self.mask = connected_to(free, self.seeds)
            return (0, occupied.shape[0], 0, occupied.shape[1])
        mask = self.mask.copy()
        mask[window[0] : window[1], window[2] : window[3]] = local
        self.mask = mask
        return window

    def _local(self, occupied: BoolGrid, patches: list[Patch], window: Box) -> BoolGrid | None:
        """The reachable cells of ``window`` after the change, or None if the change may
        have changed connectivity beyond the window."""
        row0, row1, col0, col1 = window
        free = ~occupied[row0:row1, col0:col1]
        was_free = free ^ flips_in(patches, window)
        seeds = self.seeds - np.array([row0, col0])
        inside = ((seeds >= 0) & (seeds < free.shape)).all(axis=1)
        seeds = seeds[inside]
        if not (free[seeds[:, 0], seeds[:, 1]].all() and was_free[seeds[:, 0], seeds[:, 1]].all()):
            return None
        ring = ring_of(window, occupied.shape) & free  # unchanged cells: free before and after
        terminals = np.concatenate((np.argwhere(ring), seeds))
        before, _ = ndimage.label(was_free, structure=FOUR_CONNECTED)
        after, _ = ndimage.label(free, structure=FOUR_CONNECTED)
        rows, cols = terminals[:, 0], terminals[:, 1]
        if not same_groups(before[rows, cols], after[rows, cols]):
            return None
        reached = self.mask[row0:row1, col0:col1][rows, cols]  # seeds free before: reached
        ids = np.unique(after[rows[reached], cols[reached]])
        return np.isin(after, ids[ids > 0])


def follow_changes(
    coverage: Retargets, reachable: Reachable, occupied: BoolGrid, changes: Sequence[Change]
) -> None:
    """After ``changes`` of the world: update the reachable set, retarget ``coverage`` to it."""
    window = reachable.follow(occupied, changes)
    if window != NOTHING:
        coverage.retarget(reachable.mask, window)


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


def same_groups(before: IntArray, after: IntArray) -> bool:
    """Whether two labellings split the same items into the same groups."""
    if before.size == 0:
        return True
    pairs = before.astype(np.int64) * (int(after.max()) + 1) + after
    return len(np.unique(pairs)) == len(np.unique(before)) == len(np.unique(after))
