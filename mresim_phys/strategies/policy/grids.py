"""Observation grids (phase 4, kernels): a policy robot's crop and coarse view of its map,
each in one compiled pass.

A cell's class is free, obstacle or unknown; a frontier cell is a free one that sees an
unknown 8-neighbour (``knowledge.frontiers.sees_unknown``, the frontier rule everywhere
else). The crop reads only its own cells; the coarse view reads every ``stride``-th row and
column (a regular sample: 1 in 4 cells with stride 2) and gives each coarse cell the
fraction of its sampled cells in each class, so it costs ~0.3 ms on an 800x600 map where a
full-resolution area resize of four class layers cost ~3.5 ms.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from mresim_phys.knowledge.frontiers import sees_unknown
from mresim_phys.types import FREE, OCCUPIED, UNKNOWN, BeliefGrid

CLASSES = 4  # free, obstacle, unknown, frontier


@njit(cache=True, nogil=True)
def crop_classes(belief: BeliefGrid, r0: int, c0: int, side: int) -> np.ndarray:
    """(4, side, side) uint8: the classes of the cells from (r0, c0); off the map: obstacle."""
    rows, cols = belief.shape
    out = np.zeros((CLASSES, side, side), np.uint8)
    for i in range(side):
        for j in range(side):
            r, c = r0 + i, c0 + j
            if not (0 <= r < rows and 0 <= c < cols):
                out[1, i, j] = 1
                continue
            code = belief[r, c]
            if code == FREE:
                out[0, i, j] = 1
                if sees_unknown(belief, r, c):
                    out[3, i, j] = 1
            elif code == OCCUPIED:
                out[1, i, j] = 1
            elif code == UNKNOWN:
                out[2, i, j] = 1
    return out


@njit(cache=True, nogil=True)
def coarse_fractions(belief: BeliefGrid, side: int, stride: int) -> np.ndarray:
    """(4, side, side) float32: per coarse cell, the fraction of its sampled cells (every
    ``stride``-th row and column) in each class."""
    rows, cols = belief.shape
    counts = np.zeros((CLASSES, side, side), np.int32)
    samples = np.zeros((side, side), np.int32)
    block = np.empty((cols + stride - 1) // stride, np.int64)
    for k in range(len(block)):
        block[k] = k * stride * side // cols
    for r in range(0, rows, stride):
        i = r * side // rows
        for k in range(len(block)):
            c, j = k * stride, block[k]
            samples[i, j] += 1
            code = belief[r, c]
            if code == FREE:
                counts[0, i, j] += 1
                if sees_unknown(belief, r, c):
                    counts[3, i, j] += 1
            elif code == OCCUPIED:
                counts[1, i, j] += 1
            elif code == UNKNOWN:
                counts[2, i, j] += 1
    out = np.zeros((CLASSES, side, side), np.float32)
    for i in range(side):
        for j in range(side):
            if samples[i, j] > 0:
                for k in range(CLASSES):
                    out[k, i, j] = counts[k, i, j] / samples[i, j]
    return out
