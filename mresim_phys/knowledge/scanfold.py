"""Phase 5 (sense, then map): a noiseless scan cast and folded into a map in one compiled call.

A robot scans after every point of its path, ~9 times a step at the original's speed, so a
scan's Python is paid ~70 times a step with 8 robots. The general path casts the rays
(``world.sensing.scan``: a :class:`~mresim_phys.world.space.Scan`), maybe adds range noise,
and folds them in (``knowledge.mapping.integrate_scan``): two compiled calls with Python
between them, and two hand-overs of the GIL when robots run on threads. Without noise and
without latest-observation beliefs nothing needs to happen between the two kernels, and
:func:`scan_into_map` runs both in one call: the same kernels on the same inputs, so the
same map, byte for byte. :class:`ScanQueue` goes one step further: the scans of a robot's
turn are held and cast and folded together, in order, in one call
(:func:`_cast_and_fold_many`) when its map is next read or written.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np
from numba import njit

from mresim_phys.knowledge.mapping import Update, fold_scan
from mresim_phys.planning.grid import Box
from mresim_phys.types import BeliefGrid, BoolGrid, FloatArray
from mresim_phys.world.queries import QueryFilter
from mresim_phys.world.raycast import cast_fan
from mresim_phys.world.sensing import Laser, ray_offsets
from mresim_phys.world.space import Scan, World

Pose = tuple[float, float, float]  # x, y, heading


class MapHolder(Protocol):
    """What a queue folds scans into: a robot's map and its safe cells."""

    belief: BeliefGrid
    safe: BoolGrid


@njit(cache=True, nogil=True)
def _cast_then_fold(
    grid: BoolGrid,
    ox: float,
    oy: float,
    angles: FloatArray,
    max_range: float,
    circles: FloatArray,
    belief: BeliefGrid,
    safe: BoolGrid,
    safe_radius: float,
    placed: FloatArray,
) -> tuple[int, int, BeliefGrid]:
    """``cast_fan`` from (``ox``, ``oy``) then ``fold_scan``: (row0, col0, free mask) or
    row0 = -1. ``placed`` (x, y, turn) is where the robot believes the scan was taken
    (localisation: ``localization/perceive.py``): folded from (x, y), every ray and hit
    face turned by ``turn``; equal to (ox, oy, 0), the scan folds where it was cast.
    Called only from kernels (a cached kernel that Python also calls can lose its boxing
    environment, see ``planning.dial._start_paused``): :func:`_cast_and_fold` and
    :func:`_cast_and_fold_many` are the entries from Python."""
    n = len(angles)
    ranges, normals, wall_hit = np.empty(n), np.empty((n, 2)), np.empty(n, dtype=np.bool_)
    cast_fan(grid, ox, oy, angles, max_range, circles, ranges, normals, wall_hit)
    return _place_and_fold(
        ox, oy, angles, ranges, normals, wall_hit, max_range, belief, safe, safe_radius, placed
    )


@njit(cache=True, nogil=True)
def _place_and_fold(
    ox: float,
    oy: float,
    angles: FloatArray,
    ranges: FloatArray,
    normals: FloatArray,
    wall_hit: np.ndarray,
    max_range: float,
    belief: BeliefGrid,
    safe: BoolGrid,
    safe_radius: float,
    placed: FloatArray,
) -> tuple[int, int, BeliefGrid]:
    """``fold_scan`` of a scan cast from (``ox``, ``oy``), folded from ``placed`` (x, y,
    turn): every ray and hit face turned by ``turn``. Called only from kernels."""
    radius = safe_radius
    bx, by, turn = placed[0], placed[1], placed[2]
    if bx == ox and by == oy and turn == 0.0:
        return fold_scan(ox, oy, angles, ranges, normals, wall_hit, max_range, belief, safe, radius)
    turned_angles = angles + turn
    return fold_scan(
        bx, by, turned_angles, ranges, turned(normals, turn), wall_hit, max_range, belief,
        safe, radius,
    )  # fmt: skip


@njit(cache=True, nogil=True, inline="always")
def turned(normals: FloatArray, turn: float) -> FloatArray:
    """Each (n, 2) row of ``normals`` turned by ``turn`` radians."""
    c, s = np.cos(turn), np.sin(turn)
    out = np.empty((len(normals), 2))
    for k in range(len(normals)):
        out[k, 0] = c * normals[k, 0] - s * normals[k, 1]
        out[k, 1] = s * normals[k, 0] + c * normals[k, 1]
    return out


@njit(cache=True, nogil=True)
def _fold_placed(
    ox: float,
    oy: float,
    angles: FloatArray,
    ranges: FloatArray,
    normals: FloatArray,
    wall_hit: np.ndarray,
    max_range: float,
    belief: BeliefGrid,
    safe: BoolGrid,
    safe_radius: float,
    placed: FloatArray,
) -> tuple[int, int, BeliefGrid]:
    """:func:`_place_and_fold` called from Python (a kernel of its own: see
    :func:`_cast_then_fold`)."""
    return _place_and_fold(
        ox, oy, angles, ranges, normals, wall_hit, max_range, belief, safe, safe_radius, placed
    )


def fold_placed(
    scan: Scan, heading: float, laser: Laser, belief: BeliefGrid, safe: BoolGrid, placed: Pose
) -> Update | None:
    """``integrate_scan`` of ``scan`` (cast from its origin facing ``heading``) as the
    robot places it, from its believed pose ``placed``, in one compiled call (no 'latest'
    stamps): the same map as ``integrate_scan`` of the scan moved and turned there
    (``localization/perceive.as_believed``)."""
    angles = np.ascontiguousarray(scan.angles, dtype=np.float64)
    where = placement((scan.origin[0], scan.origin[1], heading), placed)
    row0, col0, free = _fold_placed(
        float(scan.origin[0]), float(scan.origin[1]), angles, scan.ranges, scan.normals,
        scan.wall_hit, float(scan.max_range), belief, safe,
        float(laser.safe_fraction * laser.range), where,
    )  # fmt: skip
    return None if row0 < 0 else Update(row0, col0, free.view(bool))


@njit(cache=True, nogil=True)
def _cast_and_fold(
    grid: BoolGrid,
    ox: float,
    oy: float,
    angles: FloatArray,
    max_range: float,
    circles: FloatArray,
    belief: BeliefGrid,
    safe: BoolGrid,
    safe_radius: float,
    placed: FloatArray,
) -> tuple[int, int, BeliefGrid]:
    """One scan: :func:`_cast_then_fold`."""
    return _cast_then_fold(
        grid, ox, oy, angles, max_range, circles, belief, safe, safe_radius, placed
    )


@njit(cache=True, nogil=True)
def _cast_and_fold_many(
    grid: BoolGrid,
    poses: FloatArray,
    offsets: FloatArray,
    max_range: float,
    circles: FloatArray,
    belief: BeliefGrid,
    safe: BoolGrid,
    safe_radius: float,
) -> tuple[int, int, int, int]:
    """:func:`_cast_then_fold` at each row (x, y, heading, placed x, placed y, turn) of
    ``poses`` in turn, the rays at ``heading + offsets``; the union (row0, row1, col0,
    col1) of the windows of the scans that updated the map, row0 = -1 if none did."""
    r0, r1, c0, c1 = -1, -1, -1, -1
    for i in range(len(poses)):
        angles = poses[i, 2] + offsets
        row0, col0, free = _cast_then_fold(
            grid, poses[i, 0], poses[i, 1], angles, max_range, circles, belief, safe,
            safe_radius, poses[i, 3:],
        )  # fmt: skip
        if row0 >= 0:
            r0, r1, c0, c1 = grow_window((r0, r1, c0, c1), row0, col0, free)
    return r0, r1, c0, c1


@njit(cache=True, nogil=True, inline="always")
def grow_window(
    window: tuple[int, int, int, int], row0: int, col0: int, free: BeliefGrid
) -> tuple[int, int, int, int]:
    """``window`` (row0, row1, col0, col1; row0 = -1: none yet) grown to hold a scan's
    window, the ``free`` mask at (``row0``, ``col0``)."""
    r0, r1, c0, c1 = window
    h, w = free.shape
    if r0 < 0:
        return row0, row0 + h, col0, col0 + w
    return min(r0, row0), max(r1, row0 + h), min(c0, col0), max(c1, col0 + w)


def folds_in_one_call(laser: Laser, observed: np.ndarray | None) -> bool:
    """Whether a scan of ``laser`` into a map (with ``observed`` stamps or not) can take
    :func:`scan_into_map`: exact readings (no noise to draw), no latest observations to
    stamp."""
    return laser.exact and observed is None


def scan_into_map(
    world: World,
    origin: tuple[float, float],
    heading: float,
    laser: Laser,
    shape_filter: QueryFilter,
    belief: BeliefGrid,
    safe: BoolGrid,
    placed: Pose | None = None,
) -> Update | None:
    """``integrate_scan(belief, safe, scan(world, origin, heading, laser, shape_filter),
    laser.safe_fraction)`` for a laser without noise, in one compiled call; ``placed``:
    the pose the robot believes it scanned from (None: ``origin`` and ``heading``)."""
    angles = heading + ray_offsets(laser.fov_deg, laser.rays)
    grid, circles = world.ray_targets(shape_filter)
    row0, col0, free = _cast_and_fold(
        grid, float(origin[0]), float(origin[1]), angles, float(laser.range), circles,
        belief, safe, float(laser.safe_fraction * laser.range),
        placement((origin[0], origin[1], heading), placed),
    )  # fmt: skip
    return None if row0 < 0 else Update(row0, col0, free.view(bool))


def placement(cast: Pose, placed: Pose | None) -> FloatArray:
    """(x, y, turn) where a scan cast at ``cast`` is folded (``placed``; None: where it
    was cast)."""
    if placed is None or placed == cast:
        return np.array([cast[0], cast[1], 0.0])
    return np.array([placed[0], placed[1], placed[2] - cast[2]])


class ScanQueue:
    """The scans of one robot's turn, held until something reads or writes its map, then
    cast and folded in one compiled call (:meth:`fold`), in the order they were taken.

    A robot scans after every path point (~9 times a step at the original's speed);
    between those scans only its pose changes, and nothing reads its map until it replans,
    bumps into something or ends its turn. Folding them together gives the same map, byte
    for byte, as folding each at once, for a fraction of the Python and, on threads, one
    hand-over of the GIL instead of one per scan. Only for scans that
    :func:`folds_in_one_call` can take and whose updates nothing else watches (no terrain
    to learn, no path to check against each scan: ``sensing_phase.Senses.queue_for``).
    """

    def __init__(
        self, world: World, laser: Laser, shape_filter: QueryFilter, robot: MapHolder
    ) -> None:
        self.world, self.laser, self.shape_filter, self.robot = world, laser, shape_filter, robot
        self.poses: list[tuple[float, ...]] = []

    def add(
        self, position: tuple[float, float], heading: float, placed: Pose | None = None
    ) -> None:
        """Hold a scan taken at ``position`` facing ``heading`` (``placed``: the pose the
        robot believes it took it from; None: that one)."""
        cast = (float(position[0]), float(position[1]), float(heading))
        self.poses.append((*cast, *(float(v) for v in placement(cast, placed))))

    def fold(self) -> Box | None:
        """Cast and fold the held scans into the robot's map, in order; the union of the
        windows they updated (None if none did, or none was held)."""
        if not self.poses:
            return None
        poses = np.array(self.poses, dtype=np.float64)
        self.poses.clear()
        laser, robot = self.laser, self.robot
        grid, circles = self.world.ray_targets(self.shape_filter)
        r0, r1, c0, c1 = _cast_and_fold_many(
            grid, poses, ray_offsets(laser.fov_deg, laser.rays), float(laser.range), circles,
            robot.belief, robot.safe, float(laser.safe_fraction * laser.range),
        )  # fmt: skip
        return None if r0 < 0 else (r0, r1, c0, c1)
