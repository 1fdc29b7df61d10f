"""What a robot can cross (phase 4-5, a per-robot feature): its access to the ground classes.

In a scenario with a ``ground:`` block every robot holds its :class:`~.grid.Access` in
``Robot.features["ground"]``: its speed factor per class and, from the true classes, the
cells it cannot enter and the cost multipliers of those it crosses slowly.

What it knows of the classes: a robot knows the class of every cell its map holds as free
(its own scans saw the ground, or a teammate's did and the cell came with the map it
merged: a cell's class travels with the cell). Its planning reads classes only there: its
strategy's ``PlanContext`` (``strategies/base.py``) takes the cells it cannot enter out of
its passable cells (which are known free) and prices the slow ones
(:meth:`GroundView.passable`, :meth:`GroundView.slowness_with`), and the run-health
frontier check does the same. Its motion (``motion.py``) moves at its factor of the cell
it starts the step on, and never takes its centre into a cell it cannot enter: a move that
would is refused (the robot stops with its error flag set and replans; nothing is marked
in its map, as the ground there is not a wall).

The feature's value (:class:`GroundView`) is recorded as the robot's factor per class
value (``[1, 0.4, 0, 0]``: floor first) in each of its log lines; with the true classes
(the run log's ``truth.npz``) a replay has the cells it cannot enter back.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from mresim_phys.features import RobotFeature
from mresim_phys.ground.grid import Access, ClassGrid
from mresim_phys.types import BoolGrid, FloatArray


class GroundView:
    """A robot's access as its strategy sees it (applied to the cells it plans through),
    and as its snapshot records it (its factor per class: a replay has no access grids)."""

    def __init__(self, factors: tuple[float, ...], access: Access | None = None) -> None:
        self.factors = factors  # its speed factor per class value (0: floor)
        self._access = access

    def passable(self, passable: BoolGrid) -> BoolGrid:
        """``passable`` (known free cells) without the cells the robot cannot enter."""
        if self._access is None:
            return passable
        out: BoolGrid = passable & ~self._access.barred
        return out

    def slowness_with(self, terrain: FloatArray | None) -> FloatArray | None:
        """Cost multipliers of the cells it crosses slowly, times ``terrain``'s (None:
        uniform): read by its planners on the passable cells alone."""
        own = None if self._access is None else self._access.slowness
        if own is None or terrain is None:
            return terrain if own is None else own
        product: FloatArray = np.multiply(terrain, own)
        return product

    def barred_on(self, grid: ClassGrid) -> BoolGrid:
        """The cells of the class grid ``grid`` it cannot enter."""
        if self._access is not None:
            return self._access.barred
        out: BoolGrid = np.asarray(self.factors)[grid] <= 0.0
        return out


class GroundFeature(RobotFeature[Access, GroundView]):
    """A robot's access to the ground classes (module docstring)."""

    key = "ground"

    def value(self, state: Access) -> GroundView:
        """Its access, applied to the cells it plans through."""
        return GroundView(tuple(float(v) for v in state.factors), state)

    def encode(self, value: GroundView) -> Any:
        """Its factor per class value (the first, floor's, is 1)."""
        return list(value.factors)

    def decode(self, raw: Any) -> GroundView:
        """The logged factors (no access grids: :meth:`GroundView.barred_on` the truth)."""
        return GroundView(tuple(float(v) for v in raw))


GROUND = GroundFeature()
