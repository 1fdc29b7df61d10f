"""World (phase 0, events): doors that close and open during a run.

A door (``doors:`` in a scenario) is the segment between two points, ``thickness``
cells wide: the cells the segment passes through (a 4-connected line, so nothing
slips through diagonally) and those whose centre lies within half the thickness of
it. A closed door is a wall for everything (rays, motion, line of sight, path loss
and the truth grid): its cells are a movable footprint of the world
(``World.add_movable``), removed when it opens.

It is open or closed at step 0 (``closed``), changes on ``{step: N, close: NAME}``
and ``{step: N, open: NAME}`` events, and, with ``period`` and ``open_for``, cycles
by itself: open for the first ``open_for`` steps of every ``period`` (counted from
``offset``), closed for the rest. A door that should close while a robot's body is in
its way waits, open, until the doorway is clear (it never closes on a robot).
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np

from mresim_phys.types import BoolGrid
from mresim_phys.world.element_params import DoorParams
from mresim_phys.world.obstacles import ObstacleWorld

Point = tuple[float, float]


def line_cells(start: Point, end: Point) -> list[tuple[int, int]]:
    """(row, col) of every cell the segment passes through, 4-connected (Amanatides-Woo)."""
    (x0, y0), (x1, y1) = start, end
    col, row = math.floor(x0), math.floor(y0)
    end_col, end_row = math.floor(x1), math.floor(y1)
    dx, dy = x1 - x0, y1 - y0
    step_c, step_r = (1 if dx > 0 else -1), (1 if dy > 0 else -1)
    t_c = ((col + (dx > 0) - x0) / dx) if dx else math.inf
    t_r = ((row + (dy > 0) - y0) / dy) if dy else math.inf
    dt_c, dt_r = (abs(1 / dx) if dx else math.inf), (abs(1 / dy) if dy else math.inf)
    cells = [(row, col)]
    while (row, col) != (end_row, end_col) and len(cells) < 1_000_000:
        if t_c < t_r:
            col, t_c = col + step_c, t_c + dt_c
        else:
            row, t_r = row + step_r, t_r + dt_r
        cells.append((row, col))
    return cells


def door_cells(params: DoorParams) -> tuple[BoolGrid, tuple[int, int]]:
    """The door's footprint and the (row, col) of its top-left cell."""
    start, end = np.asarray(params.between[0]), np.asarray(params.between[1])
    line = np.array(line_cells(params.between[0], params.between[1]))
    half = params.thickness / 2
    pad = math.ceil(half) + 1
    row0, col0 = line.min(axis=0) - pad
    row1, col1 = line.max(axis=0) + pad + 1
    rows, cols = np.mgrid[row0:row1, col0:col1]
    centres = np.stack((cols + 0.5, rows + 0.5), axis=-1)
    direction = end - start
    length2 = float(direction @ direction)
    t = np.clip(((centres - start) @ direction) / length2, 0.0, 1.0) if length2 else 0.0
    nearest = start + np.asarray(t)[..., None] * direction
    cells = np.hypot(*np.moveaxis(centres - nearest, -1, 0)) <= half
    cells[line[:, 0] - row0, line[:, 1] - col0] = True
    keep_r, keep_c = np.flatnonzero(cells.any(axis=1)), np.flatnonzero(cells.any(axis=0))
    trimmed = cells[keep_r[0] : keep_r[-1] + 1, keep_c[0] : keep_c[-1] + 1]
    return np.ascontiguousarray(trimmed), (int(row0 + keep_r[0]), int(col0 + keep_c[0]))


class Door:
    """One door's state over a run; :meth:`apply` runs once per step in the events phase,
    after the step's close / open events have set :attr:`scheduled`."""

    kind: ClassVar[str] = "door"

    def __init__(self, params: DoorParams) -> None:
        self.params = params
        self.footprint, self.at = door_cells(params)
        self.footprint.flags.writeable = False  # shared with the world's Movable
        self.scheduled = params.closed  # the state close / open events asked for
        self.closed = False

    def apply(self, world: ObstacleWorld) -> None:
        """Close or open the door if its schedule or cycle says so (waiting if blocked)."""
        wanted = self.params.wanted_closed(world.step, self.scheduled)
        name = self.params.name
        if wanted and not self.closed:
            self.closed = world.place_obstacle(name, self.footprint, self.at, over_walls=True)
            if self.closed:
                world.log(f"door {name} closed")
        elif self.closed and not wanted:
            world.remove_obstacle(name)
            self.closed = False
            world.log(f"door {name} open")
