"""Frontier reach (phase 7, measure): which frontier cells of a robot's OWN map it could reach.

The run-health record (``knowledge/health.py``) asks this of an idle or done robot: does
its map still hold frontier cells, and could its body get next to them? A frontier cell
here is one that exploration would still go for: a cell of a frontier cluster of its map
as the strategies find them (``knowledge.frontiers``: a FREE cell that sees an UNKNOWN
8-neighbour) of at least :data:`MIN_CLUSTER` cells (the original's smallest frontier),
outside the robot's safe space (where it, or a teammate it heard from, has been: the
frontier cells there were scanned from close by and stayed, as a strategy's given-up
frontiers do). Counting every FREE cell beside an UNKNOWN one, the record called robots
idle "with reachable frontier cells" that were only one- or two-cell specks and frontiers
their strategy had reached, faced and given up (ipa_office: every such cell, checked).

Reach: the robot's passable cells at clearance = its body radius (the least margin it may
use, ``planning.fields.passable_cells``: known FREE, every known wall at least that far),
4-connected (the same sets as the planner's 8-connected moves without corner cutting: a
diagonal move is allowed only beside a passable orthogonal cell), from its position
snapped onto them (``snap_to_passable``, at most ``MAX_SNAP`` cells). A frontier cell is
*reachable* when its centre lies within ``knowledge.targets.target_reach(radius)`` of a
reached cell's centre: where every strategy may take a target to look at a frontier from
(at its least clearance). It used to be "its square within one cell of the body", a
little farther: a robot was then counted idle for 140 steps beside one frontier cell its
strategy could not take a target for (ipa_office, role_based, candidate_power 2). The
others are *closed by clearance* when the FREE cells alone (clearance 0) connect the
robot to them (the gap is narrower than its body), else *behind walls* (its map holds no
FREE way there at all: cells seen through a gap or over an obstacle).

One check is a few OpenCV passes (a dilation for the clearance, a flood fill from the
robot, a dilation for the reach) over the bounding box of the map's FREE cells: 2-4 ms on
the 800x600 maps (the second pass, at clearance 0, only when some frontier cell is out of
reach).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from mresim_phys.knowledge.frontiers import frontiers_in
from mresim_phys.knowledge.targets import reach_kernel, target_reach
from mresim_phys.planning.fields import MAX_SNAP, passable_cells, snap_to_passable
from mresim_phys.planning.grid import Box, bbox
from mresim_phys.types import FREE, BeliefGrid, BoolGrid

MIN_CLUSTER = 3  # cells: smaller frontier clusters are not counted (the original's minimum)

CLOSED, WALLED = "closed by clearance", "behind walls"


@dataclass(frozen=True)
class FrontierCheck:
    """A robot's frontier cells at one step and how many of them it could reach."""

    frontier: int  # FREE cells with an UNKNOWN 4-neighbour in its map
    reachable: int  # of those, the ones its body can get next to
    closed_by_clearance: int  # reachable through FREE cells, not with its body
    behind_walls: int  # no FREE way there in its map
    placed: bool = True  # its position snapped onto its passable cells

    @property
    def reason(self) -> str:
        """Why its unreachable frontier cells are unreachable, in a few words.

        >>> FrontierCheck(0, 0, 0, 0).reason
        'none left'
        >>> FrontierCheck(9, 2, 3, 4).reason
        'behind walls and closed by clearance'
        """
        if self.frontier == 0:
            return "none left"
        if self.reachable == self.frontier:
            return "all reachable"
        if not self.placed:
            return "no room for its body where it stands"
        parts = sorted(
            ((self.closed_by_clearance, CLOSED), (self.behind_walls, WALLED)), reverse=True
        )
        return " and ".join(text for count, text in parts if count)

    def summary(self) -> dict[str, int | str]:
        """JSON-ready counts and reason."""
        return {
            "frontier_cells": self.frontier,
            "reachable_frontier_cells": self.reachable,
            "closed_by_clearance": self.closed_by_clearance,
            "behind_walls": self.behind_walls,
            "reason": self.reason,
        }


NO_FRONTIER = FrontierCheck(0, 0, 0, 0)


def unvisited_frontier(
    belief: BeliefGrid,
    box: Box,
    crop: Box,
    safe: BoolGrid | None,
    given_up: BoolGrid | None = None,
) -> BoolGrid:
    """Within ``crop``: the cells of frontier clusters of at least :data:`MIN_CLUSTER`
    cells (``box``: the FREE cells' bounding box; the ``given_up`` cells left out before
    clustering, as the strategy leaves them) outside the safe space ``safe``."""
    found = frontiers_in(belief, box, MIN_CLUSTER, given_up)
    out = np.zeros((crop[1] - crop[0], crop[3] - crop[2]), dtype=bool)
    rows, cols = found.cells_rc[:, 0], found.cells_rc[:, 1]
    if safe is not None:
        keep = ~safe[rows, cols]
        rows, cols = rows[keep], cols[keep]
    out[rows - crop[0], cols - crop[2]] = True
    return out


def frontier_check(
    belief: BeliefGrid,
    position: tuple[float, float],
    radius: float,
    safe: BoolGrid | None = None,
    given_up: BoolGrid | None = None,
    barred: BoolGrid | None = None,
) -> FrontierCheck:
    """The frontier cells of ``belief`` and how many a robot of ``radius`` at ``position``
    (world x, y in cells) could reach (module docstring; ``safe``: its safe space;
    ``given_up``: the cells its strategy tried in vain and gave up; ``barred``: ground it
    cannot cross, ``ground/``)."""
    box = bbox(belief == FREE)
    if box is None:
        return NO_FRONTIER
    crop = grown(box, 1, belief.shape)
    frontier = unvisited_frontier(belief, box, crop, safe, given_up)
    total = int(np.count_nonzero(frontier))
    if total == 0:
        return NO_FRONTIER
    body = reached_near(belief, box, crop, position, radius, barred)
    reachable = frontier & body if body is not None else np.zeros_like(frontier)
    rest = frontier & ~reachable
    found = int(np.count_nonzero(reachable))
    loose = reached_near(belief, box, crop, position, 0.0, barred) if found < total else None
    closed = int(np.count_nonzero(rest & loose)) if loose is not None else 0
    return FrontierCheck(total, found, closed, total - found - closed, body is not None)


def grown(box: Box, margin: int, shape: tuple[int, ...]) -> Box:
    """``box`` grown by ``margin`` cells on every side, clipped to the grid."""
    r0, r1, c0, c1 = box
    return (max(r0 - margin, 0), min(r1 + margin, shape[0]),
            max(c0 - margin, 0), min(c1 + margin, shape[1]))  # fmt: skip


def reached_near(
    belief: BeliefGrid,
    free_box: Box,
    crop: Box,
    position: tuple[float, float],
    clearance: float,
    barred: BoolGrid | None = None,
) -> BoolGrid | None:
    """Within ``crop``: the cells within ``target_reach(clearance)`` (centre to centre) of
    a passable cell (at ``clearance``) 4-connected to the robot's snapped position; None if
    it snaps onto none."""
    passable, _ = passable_cells(belief, clearance, free_box)
    if barred is not None:
        passable &= ~barred
    start = snap_to_passable(passable, position, MAX_SNAP)
    if start is None:
        return None
    r0, r1, c0, c1 = crop
    cells = np.ascontiguousarray(passable[r0:r1, c0:c1]).astype(np.uint8)
    cv2.floodFill(cells, None, (start[1] - c0, start[0] - r0), 2, flags=4)  # its component
    component = (cells == 2).view(np.uint8)
    kernel = reach_kernel(target_reach(float(clearance)))
    near = cv2.dilate(component, kernel, borderType=cv2.BORDER_CONSTANT, borderValue=0)
    out: BoolGrid = near.view(bool)
    return out
