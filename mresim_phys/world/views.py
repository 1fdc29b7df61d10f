"""World (phase 8 input): what a frame needs to draw the changing parts of the world.

:func:`movable_views` lists every moving obstacle and door of a run as a
:class:`~mresim_phys.snapshot.MovableSnapshot`: where it is, whether it is on the map
(an obstacle present, a door closed) and the cells it covers, the same for a name
during the whole run (an obstacle's footprint; a door's leaf without the map's walls
its ends lie in). ``World.debris`` gives the rubble and the walls that gave way.
``Simulation.snapshot`` puts both in every snapshot; the run log stores them.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from mresim_phys.snapshot import MovableSnapshot, read_only
from mresim_phys.types import BoolGrid
from mresim_phys.world.debris import RandomDebris
from mresim_phys.world.doors import Door
from mresim_phys.world.obstacles import MovingObstacle
from mresim_phys.world.space import World


def movable_views(
    world: World, elements: Sequence[MovingObstacle | Door | RandomDebris]
) -> tuple[MovableSnapshot, ...]:
    """Every obstacle and door of ``elements`` now, in scenario order (debris: none)."""
    views = []
    for element in elements:
        if isinstance(element, MovingObstacle):
            views.append(obstacle_view(world, element))
        elif isinstance(element, Door):
            views.append(door_view(world, element))
    return tuple(views)


def obstacle_view(world: World, obstacle: MovingObstacle) -> MovableSnapshot:
    """A moving obstacle: where the world has it, else where it would enter."""
    name = obstacle.params.name
    placed = world.movables.get(name)
    at = (placed.row, placed.col) if placed is not None else obstacle.top_left(obstacle.position)
    cells = read_only(obstacle.footprint)
    return MovableSnapshot(name, "obstacle", cells, at, placed is not None)


def door_view(world: World, door: Door) -> MovableSnapshot:
    """A door: its leaf (off the map's original walls), closed if the world holds it."""
    name = door.params.name
    (x0, y0), (x1, y1) = door.params.between
    segment = ((float(x0), float(y0)), (float(x1), float(y1)))
    leaf = read_only(door_leaf(door.footprint, door.at, world.original))
    return MovableSnapshot(name, "door", leaf, door.at, name in world.movables, segment)


def door_leaf(footprint: BoolGrid, at: tuple[int, int], walls: BoolGrid) -> BoolGrid:
    """``footprint`` (top-left cell ``at``) without the cells ``walls`` holds."""
    rows, cols = walls.shape
    row, col = at
    h, w = footprint.shape
    inside = np.zeros_like(footprint)
    r0, c0 = max(row, 0), max(col, 0)
    r1, c1 = min(row + h, rows), min(col + w, cols)
    if r0 < r1 and c0 < c1:
        window = ~walls[r0:r1, c0:c1]
        inside[r0 - row : r1 - row, c0 - col : c1 - col] = window
    leaf: BoolGrid = footprint & inside
    return leaf
