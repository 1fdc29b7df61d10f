"""Mapping (phase 3, before the mission): a prior map robots know, kept apart from what they see.

A scenario's ``prior:`` gives some robots (``robots``: names or ``all``) a map of
the building before the mission: the plan, perhaps from before a collapse. It is
read like ``map:`` and degraded once per run from the run's ``prior`` stream: each
cell is dropped (left unknown) with probability ``drop``, and each kept cell flipped
(free <-> wall) with probability ``flip``. Every robot given it holds the same grid
(read-only, shared).

Prior cells are knowledge, not observations: a robot's belief grid stays what it
and its teammates observed (so the prior never counts as explored or known at the
base, is never exchanged, and the done rule does not see it). Only the robot's
planning map uses it (:func:`planning_map`): a cell its belief does not know takes
the prior's value, so paths and distance fields run through the plan's corridors,
and the first scan of a cell overrides the plan there. A robot whose sensed map
then blocks its path replans (``motion.path_blocked``). Frontier strategies may
also skip frontiers behind which the plan shows only walls (:func:`walled_in`): an
out-of-date plan then hides the space where a wall has since given way.

The prior is a per-robot feature (``features.py``): the shared grid is the state in
``Robot.features["prior"]`` of every robot given it, and its strategy sees it
(``PRIOR.of(view)``); snapshots and logs do not carry it per robot (``truth.npz`` has it).
"""

from __future__ import annotations

import cv2
import numpy as np

from mresim_phys.features import PlainFeature
from mresim_phys.types import FREE, OCCUPIED, UNKNOWN, BeliefGrid, BoolGrid

STREAM = "prior"  # the named random stream the degradation draws from


class PriorMap(PlainFeature[BeliefGrid]):
    """The map a robot knew before the mission (read-only, shared by the robots given it);
    its value is the grid itself."""

    key = "prior"
    recorded = False


PRIOR = PriorMap()


def prior_belief(
    occupied: BoolGrid, drop: float, flip: float, rng: np.random.Generator
) -> BeliefGrid:
    """The prior as a read-only belief grid (FREE / OCCUPIED / UNKNOWN where dropped)
    from a map's occupancy, with ``drop`` and ``flip`` applied from ``rng`` (two draws
    of the map's size, always made, so the rates never shift each other's draws)."""
    dropped = rng.random(occupied.shape) < drop
    flipped = rng.random(occupied.shape) < flip
    walls = occupied ^ flipped
    grid: BeliefGrid = np.where(walls, OCCUPIED, FREE).astype(np.uint8)
    grid[dropped] = UNKNOWN
    grid.flags.writeable = False
    return grid


def planning_map(belief: BeliefGrid, prior: BeliefGrid | None) -> BeliefGrid:
    """The map a robot plans on: its belief, and the prior where its belief is unknown."""
    if prior is None:
        return belief
    grid: BeliefGrid = np.where(belief == UNKNOWN, prior, belief)
    return grid


def walled_in(belief: BeliefGrid, prior: BeliefGrid) -> BoolGrid:
    """Cells none of whose UNKNOWN 8-neighbours the prior holds as anything but a wall:
    a frontier there opens onto nothing the plan knows of (cells the prior dropped
    count as open)."""
    open_unknown = (belief == UNKNOWN) & (prior != OCCUPIED)
    near: BoolGrid = cv2.dilate(open_unknown.view(np.uint8), np.ones((3, 3), np.uint8)) == 0
    return near
