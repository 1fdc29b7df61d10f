"""Communication regions (phase 6, for views): where a link to each agent would hold.

For every agent, the polygon reached by sampling its main-channel model along
``REGION_RAYS`` directions (the original's GUI range polygon: 129 rays), from
the agents' positions and the true walls. ``disk`` needs no polygon (renderers
draw its circle); for other models a :class:`RegionProbe` gives the polygons of
any snapshot, so a replayed frame draws the same regions as the live one.
"""

from __future__ import annotations

import numpy as np

from mresim_phys.comms.base import CommModel, Radios
from mresim_phys.comms.disk import DiskComm
from mresim_phys.types import FloatArray
from mresim_phys.world.space import World

REGION_RAYS = 129


def region_polygon(
    model: CommModel, radios: Radios, index: int, world: World, rays: int = REGION_RAYS
) -> FloatArray:
    """(rays, 2) polygon around agent ``index`` where its signal still holds."""
    angles = np.linspace(0.0, 2.0 * np.pi, rays, endpoint=False)
    reach = model.reach(radios, index, angles, world)
    origin = radios.positions[index]
    polygon: FloatArray = origin + reach[:, None] * np.column_stack(
        [np.cos(angles), np.sin(angles)]
    )
    return polygon


class RegionProbe:
    """The main channel's regions for agents at any positions (None for ``disk``)."""

    def __init__(self, model: CommModel, ranges: FloatArray, powers: FloatArray, world: World):
        self.model, self.ranges, self.powers, self.world = model, ranges, powers, world

    @property
    def circles(self) -> bool:
        """Whether regions are plain circles of each agent's range (the disk model)."""
        return isinstance(self.model, DiskComm)

    def __call__(self, positions: FloatArray) -> list[FloatArray | None]:
        """One polygon per agent at ``positions`` (all None for the disk model)."""
        if self.circles:
            return [None] * len(positions)
        radios = Radios(np.asarray(positions, dtype=float), self.ranges, self.powers)
        return [region_polygon(self.model, radios, i, self.world) for i in range(len(radios))]
