"""Mapping (phase 3): what a robot knows of the terrain, learned by sensing.

In a scenario with ``terrain:`` every robot holds a known factor grid (float32, the
map's shape): 1.0 (open floor) where it has not sensed the ground, and the true factor
of every cell a scan of its has marked FREE (the scan's :class:`Update`). A robot never
reads the truth otherwise; its planners use this grid (``planning.costs``). Known
terrain is not exchanged between robots (a limitation: each robot learns the ground
it has seen itself). Without terrain in the scenario there is no grid (``None``).

Known terrain is a per-robot feature (``features.py``): the grid is the state in
``Robot.features["terrain"]``, and its strategy sees it read-only (``TERRAIN.of(view)``);
snapshots and logs do not carry it (the truth's terrain is in ``truth.npz``).
"""

from __future__ import annotations

import numpy as np

from mresim_phys.features import ReadOnlyGrid
from mresim_phys.knowledge.mapping import Update
from mresim_phys.world.terrain import TerrainGrid


class KnownTerrain(ReadOnlyGrid[TerrainGrid]):
    """The terrain factors a robot knows; its strategy sees them read-only."""

    key = "terrain"
    recorded = False


TERRAIN = KnownTerrain()


def unknown_terrain(truth: TerrainGrid | None) -> TerrainGrid | None:
    """A robot's known factors at the start: all 1 (None when the run has no terrain)."""
    return None if truth is None else np.ones_like(truth)


def learn_terrain(known: TerrainGrid, truth: TerrainGrid, update: Update) -> None:
    """Copy the true factors of the cells ``update`` marked FREE into ``known``, in place."""
    h, w = update.free.shape
    rows = slice(update.row0, update.row0 + h)
    cols = slice(update.col0, update.col0 + w)
    np.copyto(known[rows, cols], truth[rows, cols], where=update.free)
