"""Tried frontiers (phase 4, decide): what a robot remembers of frontiers it reached in vain.

A robot that reaches its frontier target, faces the frontier and scans, and still holds it
as a frontier could not see the unknown cells behind it from there: round a wall's corner,
into a wall, down a laser fan narrower than its rays' spacing. It remembers the **spot** it
stood on (the cells within :data:`SPOT` of it) and counts one **try** for each chased cell
within ``give_up_radius`` of the spot:

* a cell tried once is **set aside**: the robot chases the frontiers it has not tried
  first, as the original leaves its "bad frontiers";
* when none is left, it takes up the cells set aside again, from other spots (the tried
  spots are no longer targets): the next target for a shadow is round the corner;
* a cell tried :data:`MAX_TRIES` times is **given up**: no longer a frontier for it.

A single try used to give a frontier up for good. At a wall's corner the cheapest place
within reach of the frontier lies before the corner, where nothing behind it shows, and
the team gave up the shadow behind the corner for good (the original's 12x12_rooms: every
robot `done` at 25 % explored, once rays grazing a corner no longer marked false walls
that hid those shadows). Setting aside keeps the single try's pace while untried
frontiers remain; the second try keeps `done` from coming before the shadows are looked
into.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mresim_phys.memory import sparse_zeros
from mresim_phys.types import BoolGrid, IntArray

MAX_TRIES = 2  # tries (from different spots) before a frontier cell is given up
SPOT = 1.5  # cells: a tried spot's radius (a target this close to it is the same place)


@dataclass
class Tried:
    """A robot's tried spots, the cells it set aside (tried once) and those it gave up."""

    set_aside: BoolGrid
    given_up: BoolGrid
    tries: NDArray[np.uint8]
    spots: BoolGrid
    gave_up_any: bool = False  # whether any cell is given up (read every step: no grid scan)
    set_aside_any: bool = False  # whether any cell is set aside (read every replan)

    @classmethod
    def empty(cls, shape: tuple[int, ...]) -> Tried:
        """Nothing tried yet on a map of ``shape``."""
        return cls(
            sparse_zeros(shape, bool),
            sparse_zeros(shape, bool),
            sparse_zeros(shape, np.uint8),
            sparse_zeros(shape, bool),
        )

    def failed(self, chasing: IntArray, position: tuple[float, float], radius: float) -> None:
        """The robot stood at ``position``, faced the frontier ``chasing`` (its cells) and it
        is still there: mark the spot, count a try for its cells within ``radius``; set
        them aside, and give up those tried :data:`MAX_TRIES` times."""
        x, y = position
        near = np.hypot(chasing[:, 0] + 0.5 - y, chasing[:, 1] + 0.5 - x) <= radius
        rows, cols = chasing[near, 0], chasing[near, 1]
        self.tries[rows, cols] = np.minimum(self.tries[rows, cols], MAX_TRIES - 1) + 1
        self.set_aside[rows, cols] = True
        self.set_aside_any = self.set_aside_any or len(rows) > 0
        self.given_up[rows, cols] |= self.tries[rows, cols] >= MAX_TRIES
        self.gave_up_any = self.gave_up_any or bool(self.given_up[rows, cols].any())
        self.mark_spot(position)

    def give_up(self, rows: IntArray, cols: IntArray) -> None:
        """Give the cells (rows[i], cols[i]) up at once (and set them aside)."""
        self.given_up[rows, cols] = self.set_aside[rows, cols] = True
        self.gave_up_any = self.gave_up_any or len(rows) > 0
        self.set_aside_any = self.set_aside_any or len(rows) > 0

    def mark_spot(self, position: tuple[float, float]) -> None:
        """The cells whose centres lie within :data:`SPOT` of ``position``."""
        x, y = position
        r0, r1 = max(int(y - SPOT), 0), min(int(y + SPOT) + 1, self.spots.shape[0])
        c0, c1 = max(int(x - SPOT), 0), min(int(x + SPOT) + 1, self.spots.shape[1])
        rows, cols = np.mgrid[r0:r1, c0:c1]
        self.spots[r0:r1, c0:c1] |= np.hypot(rows + 0.5 - y, cols + 0.5 - x) <= SPOT

    def target_cells(self, passable: BoolGrid) -> BoolGrid:
        """``passable`` without the tried spots."""
        out: BoolGrid = passable & ~self.spots
        return out


def tried_after_arrival(
    tried: Tried | None,
    shape: tuple[int, ...],
    reached_goal: bool,
    chasing: IntArray | None,
    position: tuple[float, float],
    radius: float,
) -> tuple[Tried, IntArray | None]:
    """(tried, chasing) once a robot is asked again: its record (made for a map of
    ``shape`` on first use), a frontier it has just reached and still holds counting a try
    within ``radius`` (and no longer chased)."""
    if tried is None:
        tried = Tried.empty(shape)
    if reached_goal and chasing is not None:
        tried.failed(chasing, position, radius)
        chasing = None
    return tried, chasing
