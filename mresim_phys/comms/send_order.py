"""Send order on bounded links (phase 6b, kernels): which queued cells make a packet's cut.

A packet carries the ``count`` cells first in the channel's priority order. Only which
cells make the cut matters, not their order within it, so the cut is a selection, not a
sort: each cell falls in a bucket (its tier, then its whole distance in cells from the
point the cells are ranked by), the buckets are counted, every cell of the buckets
before the one the cut falls in is taken, and that one bucket's cells are sorted by
squared distance (ties: the earlier in the queue) to take the rest. Two passes over the
queue and a sort of one ring of cells, where a partial sort of float keys cost 0.1-0.3
ms per packet on a 32-robot team's backlogs.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from mresim_phys.types import IntArray

NO_TIER = np.iinfo(np.int64).min  # a ``later_upto`` that puts no cell in the later tier


@njit(cache=True, nogil=True)
def cut_nearest(
    index: IntArray,
    cols: int,
    x: float,
    y: float,
    count: int,
    stamps: np.ndarray,
    later_upto: int,
) -> IntArray:
    """Positions in ``index`` (flat cells of a grid ``cols`` wide) of the ``count`` cells
    first in the order: cells whose tick in ``stamps`` (the grid's, flat) is above
    ``later_upto`` before the others (the later tier), each tier nearest (``x``, ``y``)
    first (cell centres), ties in queue order. All positions, in queue order, when
    ``count`` covers them."""
    n = len(index)
    if count >= n:
        return np.arange(n)
    squared = np.empty(n, np.float64)
    bucket = np.empty(n, np.int64)
    ring, per_row = 0, 1.0 / cols
    for k in range(n):
        # the row without an integer division: exact, as (flat + 0.5) / cols is at least
        # 0.5 / cols away from the next whole number
        row = int((index[k] + 0.5) * per_row)
        dx = index[k] - row * cols + 0.5 - x
        dy = row + 0.5 - y
        squared[k] = dx * dx + dy * dy
        bucket[k] = int(np.sqrt(squared[k]))
        ring = max(ring, bucket[k] + 1)
    for k in range(n):
        if stamps[index[k]] <= later_upto:
            bucket[k] += ring
    counts = np.zeros(2 * ring + 1, np.int64)
    for k in range(n):
        counts[bucket[k]] += 1
    edge, below = 0, 0
    while below + counts[edge] < count:
        below += counts[edge]
        edge += 1
    out = np.empty(count, np.int64)
    tied = np.empty(counts[edge], np.int64)
    taken, ties = 0, 0
    for k in range(n):
        if bucket[k] < edge:
            out[taken] = k
            taken += 1
        elif bucket[k] == edge:
            tied[ties] = k
            ties += 1
    order = np.argsort(squared[tied], kind="mergesort")
    for m in range(count - taken):
        out[taken + m] = tied[order[m]]
    return out
