"""Procedural maps (phase 0, input data): blueprints, the simple shapes of benchmark sets.

A blueprint's ``shape`` is one of ``loop`` (a corridor ring around a solid block),
``corridor`` (a straight corridor across the map's longer side), ``corner`` (an L: a
corridor along the bottom turning up the right side), ``room`` (one room in the middle of
the map, ``room`` of its width and height), or several joined by ``+``
(``loop+room``: the open space of each, drawn into one map, a room joined to the
others by a corridor across the map through its middle; what they leave apart is filled
in). Corridors are ``corridor`` cells wide, walls ``wall`` cells thick. A
blueprint draws nothing at random: its seed only places the base and the starts.
"""

from __future__ import annotations

import numpy as np

from mresim_phys.mapgen.open_ground import border, keep_largest
from mresim_phys.mapgen.params import BlueprintParams
from mresim_phys.types import BoolGrid

SHAPES = ("loop", "corridor", "corner", "room")


def blueprint(p: BlueprintParams, width: int, height: int) -> BoolGrid:
    """The occupancy grid of ``p.shape`` (module docstring)."""
    free = np.zeros((height, width), dtype=bool)
    shapes = p.shape.split("+")
    for shape in shapes:
        free |= open_space(shape, p, width, height)
    if "room" in shapes and len(set(shapes)) > 1:  # its doorways: a corridor through it
        mid = (height - p.corridor) // 2
        free[mid : mid + p.corridor, p.wall : width - p.wall] = True
    return keep_largest(border(~free, p.wall))


def open_space(shape: str, p: BlueprintParams, width: int, height: int) -> BoolGrid:
    """The open cells of one shape on a ``width x height`` map."""
    free = np.zeros((height, width), dtype=bool)
    w, c = p.wall, p.corridor
    if shape == "corridor":
        if width >= height:
            mid = (height - c) // 2
            free[mid : mid + c, w : width - w] = True
        else:
            mid = (width - c) // 2
            free[w : height - w, mid : mid + c] = True
    elif shape == "corner":
        free[height - w - c : height - w, w : width - w] = True
        free[w : height - w, width - w - c : width - w] = True
    elif shape == "loop":
        m = w + c  # the ring's outer edge one corridor in from the outer wall
        free[m : height - m, m : width - m] = True
        free[m + c : height - m - c, m + c : width - m - c] = False
    else:  # room
        rw, rh = int(width * p.room), int(height * p.room)
        x0, y0 = (width - rw) // 2, (height - rh) // 2
        free[y0 : y0 + rh, x0 : x0 + rw] = True
    return free
