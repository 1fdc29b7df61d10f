"""``line_of_sight`` (phase 6): the original's DirectLine model on exact geometry.

Linked when ``disk`` links the pair (distance < sum of ranges) and nothing
blocks the straight segment between them: one pymunk segment query against the
walls (robot bodies never block radio). ``clearance`` sweeps the segment by a
radius; the original's pixel test is a 0.5 px clearance, our default is the
exact line (0). An agent's region is its disk cut by the walls it sees.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from mresim_phys.comms.base import Radios, candidate_pairs, symmetric_links
from mresim_phys.comms.catalog import COMM_MODELS
from mresim_phys.comms.disk import disk_reach
from mresim_phys.comms.params import CommParams, LineOfSightParams
from mresim_phys.plugin import Plugin
from mresim_phys.types import FloatArray
from mresim_phys.world.space import World


@COMM_MODELS.register
class LineOfSightComm(Plugin):
    """Linked iff distance < range_i + range_j and no wall crosses the segment between them."""

    name = "line_of_sight"

    Params: ClassVar[type[CommParams]] = LineOfSightParams
    params: LineOfSightParams

    def __init__(self, params: LineOfSightParams) -> None:
        self.params = params

    def links(self, radios: Radios, world: World) -> np.ndarray:
        """Disk pairs whose sight line is clear of walls."""
        rows, cols = candidate_pairs(radios.positions, disk_reach(radios))
        walls = world.radio_filter()  # walls and the movable obstacles that block radio
        points = [tuple(p) for p in radios.positions.tolist()]
        clear = [
            world.first_hit(points[i], points[j], self.params.clearance, walls) is None
            for i, j in zip(rows.tolist(), cols.tolist(), strict=True)
        ]
        keep = np.array(clear, dtype=bool)
        return symmetric_links(len(radios), rows[keep], cols[keep])

    def reach(self, radios: Radios, index: int, angles: FloatArray, world: World) -> FloatArray:
        """The agent's disk, each ray stopped at the first wall."""
        origin = tuple(radios.positions[index].tolist())
        walls = world.radio_filter()  # as the links: radio-quiet obstacles let it through
        return world.cast_rays(origin, angles, float(radios.ranges[index]), walls).ranges
