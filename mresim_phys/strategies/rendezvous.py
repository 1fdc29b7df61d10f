"""Multi-point rendezvous (phase 4, decide): meeting points linked through walls.

The original's ``MultiPointRendezvousStrategy`` (V. Spirin, S. Cameron, "Rendezvous
through obstacles in multi-agent exploration", SSRR 2014): explorer and relay need not
stand at the same point to exchange their maps, only at two points the radio links. The
explorer keeps its single point (the improved rendezvous); the relay's point is, of the
points the robot's own comm estimate links with it (through walls too), the one whose
path to the base's range is shortest, so the relay's shuttle is short.

* **Sampled points**: quasi-random (Sobol, unscrambled: the same map gives the same
  points) known-free cells, one per ``density`` passable cells, as the original's
  sampling-based RV graph (:func:`sample_points`).
* **Link estimate**: the robot-side PropModel1 estimate of the original
  (:func:`linked`): range ``R / 1.1`` shrunk by ``10 ** (-4.015 W / 25)`` with ``W`` the
  walls on the robot's map between the two points (separate runs of occupied cells) plus
  one per :data:`UNKNOWN_PER_WALL` cells of unknown space crossed, rounded up (the
  original rounds down; measured on the library, half-known shelves then let the estimate
  link points the radio does not, and partners waited out their meetings apart).
* **Base range**: the sampled points the estimate links with the base (range: the
  robot's own comm range); path costs to them come from one multi-source search
  (``skimage.graph.MCP_Geometric``) on the robot's passable cells.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.stats import qmc
from skimage.graph import MCP_Geometric

from mresim_phys.planning.grid import Box
from mresim_phys.types import OCCUPIED, UNKNOWN, BeliefGrid, BoolGrid, FloatArray
from mresim_phys.world.walls import walls_between

RANGE_DEFLATION = 1.1  # the original's robot-side estimate: R / 1.1
WALL_DB = 4.015  # dB per wall in the robot-side estimate (the simulator's: 3.65)
EXPONENT = 2.5  # PropModel1's path-loss exponent
UNKNOWN_PER_WALL = 14.0  # cells of unknown space counted as one wall (the original's 14 px)
DENSITY = 400  # passable cells per sampled point (the original's samplingDensity)
MIN_SAMPLES = 16


@dataclass(frozen=True)
class MultiPoint:
    """A multi-point choice: both meeting points and what the choice looked at."""

    explorer: tuple[float, float]
    relay: tuple[float, float]
    candidates: FloatArray  # (k, 2) sampled points (x, y): the potential RV points
    through_walls: FloatArray  # (m, 2) sampled points linked to the explorer's through walls


def estimated_range(
    belief: BeliefGrid, start: FloatArray, ends: FloatArray, reach: float
) -> FloatArray:
    """The estimated radio range from ``start`` towards each of ``ends`` (cells)."""
    starts = np.broadcast_to(start, ends.shape).copy()
    runs, _ = walls_between(belief == OCCUPIED, starts, ends)
    _, unknown = walls_between(belief == UNKNOWN, starts, ends)
    walls = runs + np.ceil(unknown / UNKNOWN_PER_WALL)
    return np.asarray(reach / RANGE_DEFLATION * 10 ** (-WALL_DB * walls / (10 * EXPONENT)))


def linked(belief: BeliefGrid, start: FloatArray, ends: FloatArray, reach: float) -> BoolGrid:
    """Whether the robot's estimate links ``start`` with each of ``ends``."""
    if len(ends) == 0:
        return np.zeros(0, bool)
    distance = np.hypot(*(ends - start).T)
    return np.asarray(distance < estimated_range(belief, start, ends, reach))


def sample_points(passable: BoolGrid, box: Box | None, density: int = DENSITY) -> FloatArray:
    """Sobol points on passable cells, one per ``density`` of them: (k, 2) cell centres."""
    if box is None:
        return np.zeros((0, 2))
    r0, r1, c0, c1 = box
    wanted = max(MIN_SAMPLES, int(passable[r0:r1, c0:c1].sum()) // density)
    box_cells = (r1 - r0) * (c1 - c0)
    draws = wanted * max(1, box_cells // max(int(passable[r0:r1, c0:c1].sum()), 1))
    unit = qmc.Sobol(2, scramble=False).random_base2(max(1, math.ceil(math.log2(draws))))
    rows = (r0 + unit[:, 1] * (r1 - r0)).astype(int)
    cols = (c0 + unit[:, 0] * (c1 - c0)).astype(int)
    keep = passable[rows, cols]
    cells = np.unique(np.stack([rows[keep], cols[keep]], axis=1), axis=0)
    return np.asarray(cells[:, ::-1] + 0.5, dtype=float)


def costs_to(passable: BoolGrid, box: Box, sources: FloatArray) -> FloatArray:
    """Path costs over passable cells (within ``box``) to the nearest of ``sources``
    ((x, y) points); inf where none is reachable."""
    r0, r1, c0, c1 = box
    costs = np.full(passable.shape, np.inf)
    window = passable[r0:r1, c0:c1]
    starts = [
        (int(y) - r0, int(x) - c0)
        for x, y in sources
        if r0 <= int(y) < r1 and c0 <= int(x) < c1 and window[int(y) - r0, int(x) - c0]
    ]
    if starts:
        weights = np.where(window, 1.0, np.inf)
        found, _ = MCP_Geometric(weights, fully_connected=True).find_costs(starts)
        costs[r0:r1, c0:c1] = found
    return costs


def relay_point(
    belief: BeliefGrid,
    passable: BoolGrid,
    box: Box | None,
    explorer: tuple[float, float],
    base: tuple[float, float],
    reach: float,
) -> MultiPoint:
    """The relay's meeting point for the explorer's ``explorer`` point (see module doc);
    the explorer's own point when no sampled point linked with it is nearer the base's
    range (or the base's range is not known to be reachable)."""
    samples = sample_points(passable, box)
    if box is None or len(samples) == 0:
        empty = np.zeros((0, 2))
        return MultiPoint(explorer, explorer, empty, empty)
    here = np.asarray(explorer, float)
    near = samples[linked(belief, here, samples, reach)]
    in_range = samples[linked(belief, np.asarray(base, float), samples, reach)]
    choices = np.vstack([here[None, :], near])
    costs = costs_to(passable, box, np.vstack([np.asarray(base, float)[None, :], in_range]))
    rows = np.clip(choices[:, 1].astype(int), 0, passable.shape[0] - 1)
    cols = np.clip(choices[:, 0].astype(int), 0, passable.shape[1] - 1)
    cost = costs[rows, cols]
    best = 0 if not np.isfinite(cost).any() else int(np.argmin(cost))
    walls, _ = walls_between(belief == OCCUPIED, np.broadcast_to(here, near.shape).copy(), near)
    chosen = (float(choices[best, 0]), float(choices[best, 1]))
    return MultiPoint(explorer, chosen, samples, near[walls > 0])
