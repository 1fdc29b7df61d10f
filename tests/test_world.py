"""World queries: swept circles see walls the centre line misses."""

from __future__ import annotations

import numpy as np

from mresim_phys.world.space import World


def test_a_swept_circle_hits_a_wall_corner_its_centre_line_passes() -> None:
    occupied = np.zeros((60, 200), dtype=bool)
    occupied[31:, 100] = True  # a wall whose top end lies 0.5 below the line y = 30.5
    world = World(occupied, [1.0])
    walls = world.query_filter(None, robots_block=False)
    assert world.first_hit((90.5, 30.5), (110.5, 30.5), 0.0, walls) is None
    hit = world.first_hit((90.5, 30.5), (110.5, 30.5), 1.0, walls)
    assert hit is not None and hit.is_wall
    assert 0.40 < hit.alpha < 0.47  # the circle touches the corner (100, 31) near x = 99.1
    assert world.blocked((90.5, 30.5), (110.5, 30.5), 1.0, walls) is not None


def test_a_swept_circle_clear_of_walls_is_not_blocked() -> None:
    occupied = np.zeros((60, 200), dtype=bool)
    occupied[33:, 100] = True
    world = World(occupied, [1.0])
    walls = world.query_filter(None, robots_block=False)
    assert world.first_hit((90.5, 30.5), (110.5, 30.5), 1.0, walls) is None
