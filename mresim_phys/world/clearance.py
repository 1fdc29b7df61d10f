"""World (phase 5, move): a compiled test that a moving robot's swept box touches nothing.

A robot moves a cell or so per path point, ~9 times a step at the original's speed, and
each move asks Chipmunk what a circle swept along it would hit
(:class:`~mresim_phys.world.queries.SpaceQuery`): ~6 us of Python and cffi calls, under
the query lock. Chipmunk takes its candidates from the shapes whose bounding boxes touch
the swept box; with none, the answer is "nothing". Every obstacle shape lies on the
boundary of an occupied cell of the truth grid (``world/maps.py``, ``world/bodies.py``:
the invariant the exact ray cast relies on too), and robots are circles, so when no
occupied cell and no robot circle touches the box there is no candidate and the query
can be skipped: :func:`box_clear` says so in one small compiled pass, and the answer is
the same as Chipmunk's. Only moves next to a wall or a robot reach Chipmunk.
"""

from __future__ import annotations

import math

from numba import njit

from mresim_phys.types import BoolGrid, FloatArray

TOUCH_EPS = 1e-6  # cells: a box this close to a cell or circle counts as touching it


@njit(cache=True)  # keeps the GIL: a sub-microsecond call would only wait to get it back
def box_clear(
    grid: BoolGrid, circles: FloatArray, x0: float, y0: float, x1: float, y1: float
) -> bool:
    """Whether no occupied cell of ``grid`` and no circle of ``circles`` (rows x, y, r)
    touches the closed box [x0, x1] x [y0, y1] (bounding boxes touching count); a box
    reaching the map's edge is never clear (outside the map is wall)."""
    rows, cols = grid.shape
    c0, c1 = math.floor(x0 - TOUCH_EPS), math.floor(x1 + TOUCH_EPS)
    r0, r1 = math.floor(y0 - TOUCH_EPS), math.floor(y1 + TOUCH_EPS)
    if r0 < 0 or c0 < 0 or r1 >= rows or c1 >= cols:
        return False
    for r in range(r0, r1 + 1):
        for c in range(c0, c1 + 1):
            if grid[r, c]:
                return False
    for i in range(circles.shape[0]):
        x, y, radius = circles[i, 0], circles[i, 1], circles[i, 2] + TOUCH_EPS
        if x + radius >= x0 and x - radius <= x1 and y + radius >= y0 and y - radius <= y1:
            return False
    return True
