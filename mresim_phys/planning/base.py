"""Path planner contract (phase 4b): a robot's way from where it is to a chosen cell.

A planner is a plugin (``team: {planner: astar | jps | topological}``, or per robot)
built once per robot from its validated ``Params``. Strategies choose WHERE to go with
distance fields (:mod:`mresim_phys.planning`); the robot's planner finds the path it
then follows. Every planner works on the robot's configuration-space mask
(``planning.traversable``: known free cells at least radius + wall margin from known
obstacles; unknown cells are not traversable) with the move rule of
:mod:`mresim_phys.planning.grid`, and returns world points from the (snapped) start cell's
centre to the goal cell's centre, optionally shortened by line-of-sight shortcuts
(:mod:`mresim_phys.planning.smoothing`).

With known slow terrain a caller passes ``slowness`` (``planning.costs``: per-cell cost
multipliers, >= 1); planners then minimise travel time instead of length (``astar``), or
fall back to a planner that does (``jps``, ``topological``), and smoothing shortcuts only
across cells of slowness 1. Callers pass ``slowness`` only when it is not None, so a
planner written before terrain existed still works on maps without it.

Typical use: ``PLANNERS.get("jps")(PlannerParams()).plan(passable, (x, y), (row, col))``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar, Protocol, runtime_checkable

import numpy as np

from mresim_phys.planning.fields import snap_to_passable
from mresim_phys.planning.params import PlannerParams
from mresim_phys.planning.smoothing import smooth_path
from mresim_phys.plugin import Plugin
from mresim_phys.types import BoolGrid, FloatArray

MAX_SNAP = 3.0  # cells: as distance_field, a start off the passable cells snaps this far


@runtime_checkable
class Planner(Protocol):
    """A path planner: one instance per robot, built from its validated params."""

    name: ClassVar[str]
    Params: ClassVar[type[PlannerParams]]

    @property
    def params(self) -> PlannerParams:
        """The validated parameters it was built from (read only: a subclass may narrow it)."""
        ...

    def plan(
        self,
        passable: BoolGrid,
        start_xy: tuple[float, float],
        goal_rc: tuple[int, int],
        slowness: FloatArray | None = None,
    ) -> FloatArray:
        """World points (n, 2) from the start cell's centre to the goal cell's; (0, 2) if none.

        ``slowness``: terrain cost multipliers per cell (None: uniform octile costs)."""
        ...

    def info(self) -> Mapping[str, Any]:
        """Extra views for renderers (merged into ``Decision.info``), e.g. ``skeleton``."""
        ...


def no_path() -> FloatArray:
    """The empty path."""
    return np.zeros((0, 2))


def endpoints(
    passable: BoolGrid, start_xy: tuple[float, float], goal_rc: tuple[int, int]
) -> tuple[tuple[int, int], tuple[int, int]] | None:
    """Snapped start cell and goal cell, or None if either is off the passable cells."""
    start = snap_to_passable(passable, start_xy, MAX_SNAP)
    row, col = int(goal_rc[0]), int(goal_rc[1])
    rows, cols = passable.shape
    if start is None or not (0 <= row < rows and 0 <= col < cols) or not passable[row, col]:
        return None
    return start, (row, col)


class GridPlanner(Plugin):
    """Shared ``plan``: snap the ends, search (``search`` of a subclass), then smooth."""

    Params: ClassVar[type[PlannerParams]] = PlannerParams
    params: PlannerParams

    def __init__(self, params: PlannerParams) -> None:
        self.params = params

    def plan(
        self,
        passable: BoolGrid,
        start_xy: tuple[float, float],
        goal_rc: tuple[int, int],
        slowness: FloatArray | None = None,
    ) -> FloatArray:
        """World points (n, 2) from the start cell's centre to the goal cell's; (0, 2) if none."""
        ends = endpoints(passable, start_xy, goal_rc)
        if ends is None:
            return no_path()
        path = self.search(passable, *ends, slowness)
        if not (self.params.smooth and len(path)):
            return path
        return smooth_path(path, passable if slowness is None else passable & (slowness <= 1.0))

    def search(
        self,
        passable: BoolGrid,
        start: tuple[int, int],
        goal: tuple[int, int],
        slowness: FloatArray | None = None,
    ) -> FloatArray:
        """Cell-centre path between two passable cells; (0, 2) if unreachable."""
        raise NotImplementedError

    def info(self) -> Mapping[str, Any]:
        """Grid planners add nothing to the picture."""
        return {}
