"""Shared value types and the occupancy-grid cell encoding used by every phase.

Grid convention (all phases): a grid is a 2-D array indexed ``[row, col]``; cell
(row r, col c) covers x in [c, c+1) and y in [r, r+1) in world units (cells), so
its centre is ``(c + 0.5, r + 0.5)``. x grows with the column, y with the row
(downwards in an image).

Belief grids are ``uint8`` with the ordered encoding UNKNOWN < FREE < OCCUPIED,
so merging two robots' knowledge is one ``np.maximum`` (a seen obstacle beats a
seen free cell, and anything known beats unknown).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import NDArray

UNKNOWN: Final = np.uint8(0)
FREE: Final = np.uint8(1)
OCCUPIED: Final = np.uint8(2)

BoolGrid = NDArray[np.bool_]
BeliefGrid = NDArray[np.uint8]
FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]
Cell = tuple[int, int]  # row, col


@dataclass(frozen=True)
class RobotSight:
    """What the explorable area (``world/explorable.py``) needs of one robot: start (x, y),
    body radius, laser range, and the positions its start seeds from (None: found on the
    map, ``world.explorable.start_seeds``; a replay gives those of the live run, whose
    truth at the start may have been another). Here, below the snapshot that carries it."""

    start: tuple[float, float]
    radius: float
    sensor_range: float
    seeds: tuple[Cell, ...] | None = None
