"""World (phase 1, geometry): the explorable area, what the team can see from where it can go.

The denominator of ``explored`` and ``known_at_base``: the free cells that some robot can
see (line of sight, within its sensor range) from a position its body can reach.

* **Positions** of a robot of radius ``r``: the cell centres at least ``r`` from every
  occupied cell's square (and from the map's edge: outside the grid is obstacle), the
  planners' configuration space at zero wall margin (:func:`body_kernel`).
* **Reachable positions**: those 4-connected to the robot's start. A diagonal step
  between two positions whose side cells are both positions keeps its body clear all
  the way (every point of the unit square between four positions is at least as far from
  any cell outside them as one of the four centres), and a diagonal with one side cell a
  position can be driven round that cell, so 8-connected driving with the planners'
  corner rule gives the same regions. The start seeds from its own cell when that centre
  is a position, else from the neighbouring positions in sight of the start cell.
* **Seen**: a cell whose centre is within the sensor range of a reachable position and in
  its line of sight (``world/sight.py``: the closed segment touches no occupied square),
  all around: a robot can turn. The cells within :func:`sight_kernel` of a reachable
  position are seen from it whatever the map (their segments stay inside the body's clear
  disc), so only the free cells left over, in free regions that hold a reachable position,
  need a search (``sight.see_cells``).

Robots of the same radius and range share one computation (a :class:`SightGroup`, seeded
from every start); explorable = the union of the groups' seen cells.

When the truth changes, :meth:`Explorable.update` follows a box of flipped cells: the
positions change within the box grown by the body kernel, the reachable positions are
relabelled in that window (``world.reach.relabel_window``; the whole map when the change
regroups its terminals: a door closed or opened), and only the cells within sensor range
of the window are looked at again (``sight.see_again``; rows holding no free cell outside
the always-seen band are skipped). A cell seen before keeps its witness if the witness
still sees it; one not seen before is searched again only if some cell became free, and
then only towards the window. The result is the full computation's
(``tests/test_explorable.py``), so a replay that follows the net change of a step gets
the live mask. Definition, algorithm and cost: ``docs/explorable.md``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from functools import lru_cache
from typing import Protocol

import cv2
import numpy as np
from numpy.typing import NDArray
from scipy import ndimage

from mresim_phys.types import BoolGrid, Cell, IntArray, RobotSight
from mresim_phys.world.changes import Change, union_box
from mresim_phys.world.maps import FOUR_CONNECTED, connected_to
from mresim_phys.world.reach import (
    LOCAL_SHARE,
    MARGIN,
    NOTHING,
    Reachable,
    Retargets,
    area,
    flips_in,
    grown,
    relabel_window,
    ring_of,
)
from mresim_phys.world.sight import NONE, clear_line, see_again, see_cells, words
from mresim_phys.world.wallset import Box

Kernel = NDArray[np.uint8]


@dataclass
class SightGroup:
    """Robots of one radius and range: their reachable positions and the cells they see."""

    radius: float
    sensor_range: float
    seeds: IntArray  # (n, 2) row, col: the positions the starts seed from
    reach: BoolGrid = field(default_factory=lambda: np.zeros((0, 0), bool))
    near: BoolGrid = field(default_factory=lambda: np.zeros((0, 0), bool))  # sight_kernel's
    seen: BoolGrid = field(default_factory=lambda: np.zeros((0, 0), bool))
    witness: NDArray[np.int32] = field(default_factory=lambda: np.zeros(0, np.int32))
    left_rows: NDArray[np.int32] = field(default_factory=lambda: np.zeros(0, np.int32))

    def count_left(self, occupied: BoolGrid, rows: tuple[int, int]) -> None:
        """:attr:`left_rows` (each row's free cells not ``near``) for ``rows`` (from, to)."""
        cells = ~occupied[rows[0] : rows[1]] & ~self.near[rows[0] : rows[1]]
        self.left_rows[rows[0] : rows[1]] = np.count_nonzero(cells, axis=1)

    @property
    def kernel(self) -> Kernel:
        """Offsets seen from any of its positions (:func:`sight_kernel`)."""
        return sight_kernel(self.radius, self.sensor_range)


@lru_cache(maxsize=64)
def body_kernel(radius: float) -> Kernel:
    """Offsets of the cells whose square is closer than ``radius`` to a cell centre: a
    position needs every one of them free.

    >>> body_kernel(1.0)
    array([[1, 1, 1],
           [1, 1, 1],
           [1, 1, 1]], dtype=uint8)
    """
    half = max(math.ceil(radius + 0.5) - 1, 0)
    gap = np.maximum(np.abs(np.arange(-half, half + 1)) - 0.5, 0.0)
    kernel: Kernel = (gap[:, None] ** 2 + gap[None, :] ** 2 < radius * radius).astype(np.uint8)
    kernel.flags.writeable = False
    return kernel


@lru_cache(maxsize=64)
def sight_kernel(radius: float, sensor_range: float) -> Kernel:
    """Offsets within ``sensor_range`` whose segment from the centre touches only cells of
    :func:`body_kernel`: seen from every position, whatever else the map holds.

    >>> sight_kernel(0.5, 10.0)
    array([[1]], dtype=uint8)
    """
    body = body_kernel(radius)
    half = body.shape[0] // 2
    walls = body == 0
    out = np.zeros_like(body)
    for dr in range(-half, half + 1):
        for dc in range(-half, half + 1):
            near = dr * dr + dc * dc <= sensor_range * sensor_range
            if near and body[half + dr, half + dc]:
                out[half + dr, half + dc] = clear_line(walls, half, half, half + dr, half + dc)
    out.flags.writeable = False
    return out


def dilated(grid: BoolGrid, kernel: Kernel, box: Box, outside: bool) -> BoolGrid:
    """``grid`` dilated by the symmetric ``kernel``, over ``box`` (cells beyond the map's
    edge count as ``outside``)."""
    half = kernel.shape[0] // 2
    row0, row1, col0, col1 = box
    rows, cols = grid.shape
    a0, a1 = max(row0 - half, 0), min(row1 + half, rows)
    b0, b1 = max(col0 - half, 0), min(col1 + half, cols)
    pad = ((a0 - row0 + half, row1 + half - a1), (b0 - col0 + half, col1 + half - b1))
    if any(pad[0] + pad[1]):
        window = np.pad(grid[a0:a1, b0:b1], pad, constant_values=outside)
    else:  # inside the map: a copy is cheaper than np.pad
        window = np.ascontiguousarray(grid[a0:a1, b0:b1])
    if half == 0:
        return window & bool(kernel[0, 0])
    out = cv2.dilate(window.view(np.uint8), kernel)[half:-half, half:-half]
    return np.ascontiguousarray(out).view(bool)


def positions(
    occupied: BoolGrid, radius: float, box: Box | None = None, no_go: BoolGrid | None = None
) -> BoolGrid:
    """The cells of ``box`` (the whole map if None) whose centres are positions of a body
    of ``radius`` (``no_go``: cells no robot may enter, ground no robot crosses)."""
    box = box or (0, occupied.shape[0], 0, occupied.shape[1])
    places = ~dilated(occupied, body_kernel(radius), box, outside=True)
    return places if no_go is None else places & ~cut(no_go, box)


def start_seeds(
    occupied: BoolGrid, places: BoolGrid, start: tuple[float, float]
) -> tuple[Cell, ...]:
    """The positions a start at ``start`` (x, y, inside the map) seeds from: its own cell
    if that is a position, else the neighbouring positions in sight of its cell (none: it
    reaches nothing)."""
    rows, cols = occupied.shape
    row, col = math.floor(start[1]), math.floor(start[0])
    if places[row, col]:
        return ((row, col),)
    return tuple(
        (r, c)
        for r in range(max(row - 1, 0), min(row + 2, rows))
        for c in range(max(col - 1, 0), min(col + 2, cols))
        if places[r, c] and clear_line(occupied, row, col, r, c)
    )


def seeded(occupied: BoolGrid, places: BoolGrid, robot: RobotSight) -> RobotSight:
    """``robot`` with its seeds (:func:`start_seeds` unless it has them)."""
    if robot.seeds is not None:
        return robot
    return replace(robot, seeds=start_seeds(occupied, places, robot.start))


def free_components(occupied: BoolGrid) -> IntArray:
    """Labels of the 4-connected free regions (0: occupied)."""
    labels = ndimage.label(~occupied, structure=FOUR_CONNECTED)[0]
    return np.asarray(labels, dtype=np.intp)


def whole(shape: tuple[int, int]) -> Box:
    """The box of a whole map of ``shape``."""
    return (0, shape[0], 0, shape[1])


def cut(grid: np.ndarray, box: Box) -> np.ndarray:
    """The view of ``grid`` inside ``box``."""
    return grid[box[0] : box[1], box[2] : box[3]]


def joined(a: Box, b: Box) -> Box:
    """The box around ``a`` and ``b``."""
    return (min(a[0], b[0]), max(a[1], b[1]), min(a[2], b[2]), max(a[3], b[3]))


class Explorable:
    """The explorable cells of a team on a map (:attr:`mask`), followed across changes;
    :attr:`robots` are the robots given, with their seeds."""

    def __init__(
        self, occupied: BoolGrid, robots: Sequence[RobotSight], no_go: BoolGrid | None = None
    ) -> None:
        self.shape: tuple[int, int] = (int(occupied.shape[0]), int(occupied.shape[1]))
        self.no_go = no_go  # cells no robot may enter (ground classes; static)
        self.places = {r.radius: positions(occupied, r.radius, no_go=no_go) for r in robots}
        self.robots = [seeded(occupied, self.places[r.radius], r) for r in robots]
        groups: dict[tuple[float, float], SightGroup] = {}
        for robot in self.robots:
            cells = np.array(robot.seeds, dtype=np.intp).reshape(-1, 2)
            key = (robot.radius, robot.sensor_range)
            if key in groups:
                groups[key].seeds = np.concatenate([groups[key].seeds, cells])
            else:
                groups[key] = SightGroup(robot.radius, robot.sensor_range, cells)
        self.groups = list(groups.values())
        self.relabels = 0  # how often a change needed a group computed again
        self.mask = np.zeros(self.shape, dtype=bool)
        self.refresh(occupied, again=False)

    def refresh(self, occupied: BoolGrid, again: bool = True) -> None:
        """Compute everything afresh on ``occupied`` (the seeds stay those of the start;
        ``again``: the positions too)."""
        for radius in self.places if again else ():
            self.places[radius] = positions(occupied, radius, no_go=self.no_go)
        labels = free_components(occupied)
        for group in self.groups:
            self._compute(occupied, group, labels)
        self._unite(whole(self.shape))

    def _compute(self, occupied: BoolGrid, group: SightGroup, labels: IntArray) -> None:
        """Compute ``group`` afresh on the whole map (``labels``: the free regions)."""
        places = self.places[group.radius]
        group.reach = connected_to(places, group.seeds)
        group.near = dilated(group.reach, group.kernel, whole(self.shape), outside=False)
        group.seen = group.near.copy()
        group.left_rows = np.zeros(self.shape[0], dtype=np.int32)
        group.count_left(occupied, (0, self.shape[0]))
        if group.witness.size != occupied.size:
            group.witness = np.full(occupied.size, NONE, dtype=np.int32)
        seeds = group.seeds[places[group.seeds[:, 0], group.seeds[:, 1]]]
        regions = np.unique(labels[seeds[:, 0], seeds[:, 1]])  # the reachable positions'
        hopeful = np.isin(labels, regions[regions > 0])
        cells = np.argwhere(hopeful & ~group.seen).astype(np.int64)
        sensor = float(group.sensor_range)
        see_cells(occupied, group.reach, cells, sensor, group.witness, group.seen)

    def _unite(self, box: Box) -> None:
        """The mask inside ``box``: the union of the groups' seen cells."""
        region = cut(self.mask, box)
        region[...] = False
        for group in self.groups:
            region |= cut(group.seen, box)

    def follow(self, occupied: BoolGrid, changes: Sequence[Change]) -> tuple[Box, BoolGrid | None]:
        """Bring :attr:`mask` up to date with ``changes`` (``occupied``: the truth after
        them); the box outside which it did not change and what it held there before."""
        patches = [patch for change in changes for patch in change.patches]
        if not patches:
            return NOTHING, None
        box = union_box(patches)
        return self.update(occupied, box, flips_in(patches, box))

    def update(self, occupied: BoolGrid, box: Box, flips: BoolGrid) -> tuple[Box, BoolGrid]:
        """Follow the cells of ``box`` flipped where ``flips`` is True (``occupied``: the
        truth after); a box holding ``box`` and every cell where :attr:`mask` changed, and
        what the mask held there before (it is changed in place)."""
        grew = bool((flips & ~cut(occupied, box)).any())
        before = {radius: self._move_places(occupied, radius, box) for radius in self.places}
        changed = box
        labels: IntArray | None = None
        for group in self.groups:
            window = self._follow(occupied, group, box, flips, grew, before[group.radius])
            if window is None:
                self.relabels += 1
                labels = free_components(occupied) if labels is None else labels
                self._compute(occupied, group, labels)
                window = whole(self.shape)
            if window != NOTHING:
                changed = joined(changed, window)
        held = cut(self.mask, changed).copy()
        self._unite(changed)
        return changed, held

    def _move_places(self, occupied: BoolGrid, radius: float, box: Box) -> tuple[Box, BoolGrid]:
        """Recompute the positions of ``radius`` around ``box``; (window, what it held)."""
        window = grown(box, body_kernel(radius).shape[0] // 2, self.shape)
        region = cut(self.places[radius], window)
        held = region.copy()
        region[...] = positions(occupied, radius, window, self.no_go)
        return window, held

    def _follow(
        self,
        occupied: BoolGrid,
        group: SightGroup,
        box: Box,
        flips: BoolGrid,
        grew: bool,
        moved: tuple[Box, BoolGrid],
    ) -> Box | None:
        """Follow a change locally: the box where ``group.seen`` changed (NOTHING: nowhere),
        or None (nothing changed yet) when its reachable positions need the whole map."""
        window = grown(moved[0], MARGIN, self.shape)
        if area(window) > LOCAL_SHARE * occupied.size:
            return None
        now = np.ascontiguousarray(cut(self.places[group.radius], window))
        was = now.copy()
        inner = shifted(moved[0], window)
        cut(was, inner)[...] = moved[1]
        local = np.zeros(now.shape, dtype=bool)
        seeds = (group.seeds - np.array([window[0], window[2]])).astype(np.int64)
        ring = ring_of(window, self.shape)
        if not relabel_window(now, was, ring, seeds, cut(group.reach, window), local):
            return None
        cut(group.reach, window)[...] = local
        return self._look_again(occupied, group, window, box, flips, grew)

    def _look_again(
        self, occupied: BoolGrid, group: SightGroup, window: Box, box: Box, flips: BoolGrid,
        grew: bool,
    ) -> Box:  # fmt: skip
        """Decide again the cells within sensor range of ``window`` (where the reachable
        positions changed; ``box``: the flipped cells); the box where ``group.seen``
        changed (NOTHING: nowhere)."""
        kernel = group.kernel
        near = grown(window, kernel.shape[0] // 2, self.shape)  # holds the flipped cells
        cut(group.near, near)[...] = dilated(group.reach, kernel, near, outside=False)
        group.count_left(occupied, (near[0], near[1]))
        margin = max(math.ceil(group.sensor_range), kernel.shape[0] // 2) + 1
        around = grown(window, margin, self.shape)
        changed = see_again(
            occupied, group.reach, group.near, group.seen, group.witness,
            np.array(around, dtype=np.int64), np.ascontiguousarray(flips),
            np.array([box[0], box[2]], dtype=np.int64), grew,
            np.array(window, dtype=np.int64), float(group.sensor_range),
            (words(occupied), words(group.near), words(group.seen)), group.left_rows,
            np.array(near[:2], dtype=np.int64),
        )  # fmt: skip
        if changed[0] >= changed[1]:
            return NOTHING
        return (int(changed[0]), int(changed[1]), int(changed[2]), int(changed[3]))


def shifted(box: Box, frame: Box) -> Box:
    """``box`` in the coordinates of the window ``frame``."""
    return (box[0] - frame[0], box[1] - frame[0], box[2] - frame[2], box[3] - frame[2])


def explorable_mask(occupied: BoolGrid, robots: Sequence[RobotSight]) -> BoolGrid:
    """The explorable cells of ``robots`` on ``occupied`` (:class:`Explorable`)."""
    return Explorable(occupied, robots).mask


class RetargetsBoth(Retargets, Protocol):
    """A counter of the explorable cells and of the connected ones (``Coverage``)."""

    def retarget_connected(
        self, connected: BoolGrid, window: Box | None = None, before: BoolGrid | None = None
    ) -> None:
        """Count the second set against ``connected`` from now on (as ``retarget``)."""
        ...


def follow_world(
    coverage: RetargetsBoth,
    reachable: Reachable,
    explorable: Explorable,
    occupied: BoolGrid,
    changes: Sequence[Change],
) -> None:
    """After ``changes`` of the world: update the connected cells and the explorable area,
    retarget ``coverage`` to both (the one call the simulation makes after changes)."""
    window, before = reachable.follow(occupied, changes)
    if window != NOTHING:
        coverage.retarget_connected(reachable.mask, window, before)
    window, held = explorable.follow(occupied, changes)
    if window != NOTHING:
        coverage.retarget(explorable.mask, window, held)
