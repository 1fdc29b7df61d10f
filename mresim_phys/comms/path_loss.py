"""``path_loss`` (phase 6): log-distance path loss with wall attenuation (paper, section 2.6).

The Bahl-Padmanabhan (RADAR, 2000) model the original calls PropModel1, as the
standard formula for the signal of agent i received at agent j::

    S_ij = P_i - 10 n log10(d / d0_i) - min(W, C) * WAF

``P_i`` is the signal at the reference distance ``d0_i`` (the agent's
``comm_range``; its ``comm_power_dbm``, else ``reference_dbm``), ``n`` the path-loss
exponent, ``W`` the walls crossed by the straight line on the true grid and ``C``
their cap. A pair is linked when the signal is at least ``cutoff_dbm`` BOTH ways
(so heterogeneous radios give symmetric links; the original used the range of
the lower-indexed robot only). With the defaults (-93 dBm at R, n = 2.5,
3.65 dB per wall, C = 125, cut-off -93 dBm) a link holds when
``d < R * 10 ** (-3.65 W / 25) = R * 0.714 ** W``, as in the original.

``walls: count`` counts separate obstacle runs (a thick wall once, as the
original); ``walls: thickness`` charges ``cell_db`` per cell of wall the line
passes through instead, so thick concrete attenuates more than a thin partition
(the cap then applies to cells).
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from mresim_phys.comms.base import Radios, candidate_pairs, pair_distances, symmetric_links
from mresim_phys.comms.catalog import COMM_MODELS
from mresim_phys.comms.params import CommParams, PathLossParams
from mresim_phys.plugin import Plugin
from mresim_phys.types import FloatArray, IntArray
from mresim_phys.world.space import World
from mresim_phys.world.walls import reach_along_rays, walls_between


@COMM_MODELS.register
class PathLossComm(Plugin):
    """Linked iff the path-loss signal is at or above the cut-off in both directions."""

    name = "path_loss"

    Params: ClassVar[type[CommParams]] = PathLossParams
    params: PathLossParams

    def __init__(self, params: PathLossParams) -> None:
        self.params = params

    def budgets(self, radios: Radios) -> FloatArray:
        """Per agent, dB to spend between its reference signal and the cut-off."""
        powers = np.where(np.isnan(radios.powers), self.params.reference_dbm, radios.powers)
        return powers - self.params.cutoff_dbm

    def free_reach(self, radios: Radios) -> FloatArray:
        """Per agent, how far its signal carries with no wall in the way."""
        return radios.ranges * 10.0 ** (self.budgets(radios) / (10.0 * self.params.exponent))

    def attenuation(self, runs: FloatArray, inside: FloatArray) -> FloatArray:
        """Wall loss (dB) of segments that crossed ``runs`` walls and ``inside`` cells of wall."""
        p = self.params
        if p.walls == "thickness":
            return np.minimum(inside, p.max_walls) * p.cell_db
        return np.minimum(runs, p.max_walls) * p.wall_db

    def signal(self, radios: Radios, sender: IntArray, distance: FloatArray) -> FloatArray:
        """Free-space signal (dBm) of each ``sender`` at ``distance``, before walls."""
        powers = self.budgets(radios)[sender] + self.params.cutoff_dbm
        ratio = np.maximum(distance, 1e-9) / np.maximum(radios.ranges[sender], 1e-9)
        return powers - 10.0 * self.params.exponent * np.log10(ratio)

    @property
    def cutoff_dbm(self) -> float:
        """The weakest signal (dBm) that still links."""
        return self.params.cutoff_dbm

    def pair_signals(
        self, radios: Radios, world: World, rows: IntArray, cols: IntArray
    ) -> FloatArray:
        """The weaker direction's signal (dBm) through the walls of each pair (rows[k],
        cols[k]): what shadowing and fading add to (``comms/radio.py``)."""
        positions = radios.positions
        runs, inside = walls_between(world.radio_occupied, positions[rows], positions[cols])
        distance = pair_distances(positions)[rows, cols]
        loss = self.attenuation(runs.astype(float), inside)
        weaker = np.minimum(
            self.signal(radios, rows, distance), self.signal(radios, cols, distance)
        )
        signals: FloatArray = weaker - loss
        return signals

    def links(self, radios: Radios, world: World) -> np.ndarray:
        """Pairs that hear each other above the cut-off through the walls between them."""
        reach = self.free_reach(radios)
        rows, cols = candidate_pairs(radios.positions, np.minimum.outer(reach, reach))
        keep = self.pair_signals(radios, world, rows, cols) >= self.params.cutoff_dbm
        return symmetric_links(len(radios), rows[keep], cols[keep])

    def reach(self, radios: Radios, index: int, angles: FloatArray, world: World) -> FloatArray:
        """Per direction, where the agent's signal through the walls drops below the cut-off."""
        p = self.params
        per_cell = p.walls == "thickness"
        x, y = radios.positions[index]
        return reach_along_rays(
            world.radio_occupied,
            float(x),
            float(y),
            np.ascontiguousarray(angles, dtype=np.float64),
            float(self.budgets(radios)[index]),
            10.0 * p.exponent,
            float(radios.ranges[index]),
            p.cell_db if per_cell else p.wall_db,
            float(p.max_walls),
            per_cell,
        )
