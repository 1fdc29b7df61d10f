"""The part of a robot's map it has written (phase 4b, knowledge): where its FREE cells lie.

A replan crops every grid pass (C-space, frontiers, regions) to the bounding box of its
robot's FREE cells (``strategies.base.PlanContext.free_box``). Found over the whole grid,
that box cost a replan 4 ms on a campus of 4000 x 4000 cells, whatever the robot knew: a
fifth of a 128-robot step. The feature :data:`KNOWN_AREA` keeps, per robot, a box that
holds the windows of its scans (grown by ``parallel.Effects``, the same windows the team
coverage recounts) and the cells merges changed (``comms.exchange.deliver``). Every FREE
cell of a robot's map got there by one of those (a bump only marks a wall), so the bounding
box is found inside that box, in time that follows what the robot knows. Its value, the
box (None: nothing written yet), is what strategies see; logs and snapshots do not record
it. Code that writes a robot's map outside the simulation's phases (a test, a what-if
script) grows the box itself with :func:`grow_known`, as such a write is also unknown to the
comm ledger and the coverage metric. With ``MRESIM_CHECK_KNOWN_AREA=1`` every lookup is
checked against the whole grid (for tests: a write path that forgot to grow the box fails
loudly).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, TypeVar

import numpy as np

from mresim_phys.features import RobotFeature
from mresim_phys.planning.grid import Box, bbox, union_box
from mresim_phys.types import FREE, BeliefGrid

CHECK = "MRESIM_CHECK_KNOWN_AREA"
T = TypeVar("T")


@dataclass
class KnownArea:
    """A box holding every cell a robot's scans and merges changed, so every FREE cell of
    its map (None: none yet; a bump's wall mark may lie outside)."""

    box: Box | None = None

    def grow(self, box: Box) -> None:
        """Cells inside ``box`` may have changed."""
        self.box = union_box(self.box, box)


class KnownAreaFeature(RobotFeature[KnownArea, "Box | None"]):
    """The box a robot's map has changed in (module docstring)."""

    key = "known_area"
    recorded = False

    def value(self, state: KnownArea) -> Box | None:
        """The box."""
        return state.box


KNOWN_AREA = KnownAreaFeature()


def grow_known(states: Mapping[str, Any], box: Box) -> None:
    """A robot (its feature ``states``) may have changed its map inside ``box``."""
    known = KNOWN_AREA.state_of(states)
    if known is not None:
        known.grow(box)


def free_box(belief: BeliefGrid, features: Mapping[str, Any]) -> Box | None:
    """The bounding box of ``belief``'s FREE cells (None: none), looked for inside the
    robot's known area when its view's ``features`` carry one, else over the whole grid."""
    return _inside_known(belief, features, _free_bbox)


def free_count(belief: BeliefGrid, features: Mapping[str, Any]) -> int:
    """How many of ``belief``'s cells are FREE, counted inside the robot's known area when
    its view's ``features`` carry one, else over the whole grid (the mission-complete rule
    asks at every replan after its first steps: 5 ms a call over a campus's 16 million
    cells)."""
    return _inside_known(
        belief, features, lambda window, r0, c0: int(np.count_nonzero(window == FREE))
    )


def _free_bbox(window: BeliefGrid, r0: int, c0: int) -> Box | None:
    """The bounding box of the FREE cells of ``window`` (whose first cell is (r0, c0))."""
    inner = bbox(window == FREE)
    return None if inner is None else (inner[0] + r0, inner[1] + r0, inner[2] + c0, inner[3] + c0)


def _inside_known(
    belief: BeliefGrid, features: Mapping[str, Any], measure: Callable[[BeliefGrid, int, int], T]
) -> T:
    """``measure(window, row0, col0)`` of the robot's known area (an empty window while it
    knows nothing), or of the whole grid when its view's ``features`` carry none; in the
    check mode, compared with the whole grid's."""
    if KNOWN_AREA.key not in features:
        return measure(belief, 0, 0)
    known: Box | None = features[KNOWN_AREA.key]
    r0, r1, c0, c1 = known if known is not None else (0, 0, 0, 0)
    found = measure(belief[r0:r1, c0:c1], r0, c0)
    if os.environ.get(CHECK) == "1":
        whole = measure(belief, 0, 0)
        if whole != found:
            raise AssertionError(f"FREE cells outside the known area {known}: {whole} != {found}")
    return found
