"""``disk`` (phase 6): the original's StaticCircle model, walls ignored.

Two agents are linked when their distance is below the SUM of their two comm
ranges (the original's semantics: each range is a disk around its agent and the
link holds when the disks overlap). Symmetric by construction. An agent's
region is its own disk.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from mresim_phys.comms.base import Radios, pair_distances, without_self_links
from mresim_phys.comms.catalog import COMM_MODELS
from mresim_phys.comms.params import CommParams, DiskParams
from mresim_phys.plugin import Plugin
from mresim_phys.types import FloatArray
from mresim_phys.world.space import World


def disk_reach(radios: Radios) -> FloatArray:
    """(n, n) sums of ranges: the distance below which two agents are within each other's disk."""
    return radios.ranges[:, None] + radios.ranges[None, :]


@COMM_MODELS.register
class DiskComm(Plugin):
    """Linked iff distance < range_i + range_j."""

    name = "disk"

    Params: ClassVar[type[CommParams]] = DiskParams
    params: DiskParams

    def __init__(self, params: DiskParams) -> None:
        self.params = params

    def links(self, radios: Radios, world: World) -> np.ndarray:
        """Pairs closer than the sum of their ranges."""
        return without_self_links(pair_distances(radios.positions) < disk_reach(radios))

    def reach(self, radios: Radios, index: int, angles: FloatArray, world: World) -> FloatArray:
        """The agent's own disk: its range in every direction."""
        return np.full(len(angles), radios.ranges[index])
