"""Run logs (output edge): which cells of a grid changed since the last logged step.

The run log stores each agent's grids (belief, safe space, skeleton, given-up frontier)
as the cells that changed since the previous logged step (``output/logformat.py``); a
sweep's run logs every step of every robot, so this comparison runs four times per robot
per step. :func:`diff_into` compares eight cells at a time (the grids as 64-bit words),
then the cells of the words that differ, updates the writer's copy and returns the
changed cells and their gaps (the form the log stores) in one compiled pass: on an
800x600 grid with 100 changed cells ~22 us, against ~48 us for the numpy word compare it
replaced, whose separate gap encoding (``np.diff``) cost as much again.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

from mresim_phys.types import IntArray


def diff_into(copy: NDArray[np.uint8], grid: np.ndarray) -> tuple[IntArray, IntArray]:
    """Sorted flat indices where ``grid`` (uint8 or bool) differs from ``copy`` (flat
    uint8), and their gaps (each index less the one before; the first less 0); ``copy``
    is then updated to match.

    >>> copy = np.zeros(12, np.uint8)
    >>> grid = np.zeros(12, bool)
    >>> grid[[3, 9, 11]] = True
    >>> idx, gaps = diff_into(copy, grid)
    >>> idx.tolist(), gaps.tolist(), copy.nonzero()[0].tolist()
    ([3, 9, 11], [3, 6, 2], [3, 9, 11])
    """
    cur = np.ascontiguousarray(grid).reshape(-1).view(np.uint8)
    n = copy.size - copy.size % 8
    return _diff(copy, cur, copy[:n].view(np.uint64), cur[:n].view(np.uint64))


@njit(cache=True, nogil=True)
def _diff(
    copy: NDArray[np.uint8],
    cur: NDArray[np.uint8],
    copy8: NDArray[np.uint64],
    cur8: NDArray[np.uint64],
) -> tuple[IntArray, IntArray]:
    """:func:`diff_into` on the grids as bytes and as words (the first ``8 * len(copy8)``
    bytes): the differing words first, then their bytes, then the bytes past the words."""
    words = np.empty(copy8.size, np.int64)
    k = 0
    for w in range(copy8.size):
        if copy8[w] != cur8[w]:
            words[k] = w
            k += 1
    n8 = copy8.size * 8
    idx = np.empty(k * 8 + copy.size - n8, np.int64)
    found = 0
    for j in range(k):
        for i in range(words[j] * 8, words[j] * 8 + 8):
            if copy[i] != cur[i]:
                idx[found] = i
                found += 1
    for i in range(n8, copy.size):
        if copy[i] != cur[i]:
            idx[found] = i
            found += 1
    gaps = np.empty(found, np.int64)
    last = 0
    for j in range(found):
        i = idx[j]
        copy[i] = cur[i]
        gaps[j] = i - last
        last = i
    return idx[:found], gaps
