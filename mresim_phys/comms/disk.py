"""``disk``: the original's StaticCircle model, walls ignored.

Two agents are linked when their distance is below the SUM of their two comm
ranges (the original's semantics: each range is a disk around its agent and the
link holds when the disks overlap). Symmetric by construction.
"""

from __future__ import annotations

import numpy as np

from ..types import FloatArray
from ..world import World
from .base import COMM_MODELS, CommParams, pair_distances, without_self_links


class DiskParams(CommParams):
    """The disk model has no parameters: ranges come from each agent."""


@COMM_MODELS.register("disk")
class DiskComm:
    """Linked iff distance < range_i + range_j."""

    Params = DiskParams

    def __init__(self, params: DiskParams) -> None:
        self.params = params

    def links(self, positions: FloatArray, ranges: FloatArray, world: World) -> np.ndarray:
        """Pairs closer than the sum of their ranges."""
        reach = ranges[:, None] + ranges[None, :]
        return without_self_links(pair_distances(positions) < reach)
