"""Phase 5 (sense, then map): scans read through the beam model, cast and folded in one call.

A robot whose laser has a beam model (``world/beam.py``) scans ~9 times a step like any
other. :class:`BeamScanQueue` holds the scans of its turn as :class:`~.scanfold.ScanQueue`
does and, when its map is next read or written, draws every held scan's uniforms from
the robot's ``sensing`` stream (scan after scan, :data:`~mresim_phys.world.beam.DRAWS` a
ray, so the draws are those of reading each scan at once) and casts, reads and folds them
in order in one compiled call: the same kernels as the general path (``cast_fan``,
``read_rays``, ``knowledge.evidence.place_evidence``), so the same map, byte for byte, and
the same counts of readings.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from mresim_phys.knowledge.evidence import place_evidence
from mresim_phys.knowledge.scanfold import MapHolder, ScanQueue, grow_window
from mresim_phys.planning.grid import Box
from mresim_phys.types import BeliefGrid, BoolGrid, FloatArray
from mresim_phys.world.beam import DRAWS, Beam, read_rays
from mresim_phys.world.queries import QueryFilter
from mresim_phys.world.raycast import cast_fan
from mresim_phys.world.sensing import Laser, ray_offsets
from mresim_phys.world.space import World


@njit(cache=True, nogil=True)
def _cast_read_fold(
    grid: BoolGrid,
    pose: FloatArray,
    offsets: FloatArray,
    max_range: float,
    circles: FloatArray,
    belief: BeliefGrid,
    safe: BoolGrid,
    safe_radius: float,
    params: FloatArray,
    draws: FloatArray,
    counts: np.ndarray,
    evidence: np.ndarray,
) -> tuple[int, int, BeliefGrid]:
    """One scan at ``pose`` (x, y, heading, placed x, placed y, turn): cast, read through
    the beam model, weighed into the map (``knowledge/evidence.py``); (row0, col0, free
    mask) or row0 = -1."""
    angles = pose[2] + offsets
    n = len(angles)
    ranges, normals, wall_hit = np.empty(n), np.empty((n, 2)), np.empty(n, dtype=np.bool_)
    cast_fan(grid, pose[0], pose[1], angles, max_range, circles, ranges, normals, wall_hit)
    read_rays(ranges, normals, wall_hit, max_range, params, draws, counts)
    return place_evidence(
        pose[0], pose[1], angles, ranges, normals, wall_hit, max_range, belief, safe,
        safe_radius, evidence, pose[3:],
    )  # fmt: skip


@njit(cache=True, nogil=True)
def _cast_read_fold_many(
    grid: BoolGrid,
    poses: FloatArray,
    offsets: FloatArray,
    max_range: float,
    circles: FloatArray,
    belief: BeliefGrid,
    safe: BoolGrid,
    safe_radius: float,
    params: FloatArray,
    draws: FloatArray,
    counts: np.ndarray,
    evidence: np.ndarray,
) -> tuple[int, int, int, int]:
    """:func:`_cast_read_fold` at each row of ``poses`` in turn (scan ``i`` reads
    ``draws[i]``); the union (row0, row1, col0, col1) of the windows of the scans that
    updated the map, row0 = -1 if none did."""
    r0, r1, c0, c1 = -1, -1, -1, -1
    for i in range(len(poses)):
        row0, col0, free = _cast_read_fold(
            grid, poses[i], offsets, max_range, circles, belief, safe, safe_radius, params,
            draws[i], counts, evidence,
        )  # fmt: skip
        if row0 >= 0:
            r0, r1, c0, c1 = grow_window((r0, r1, c0, c1), row0, col0, free)
    return r0, r1, c0, c1


class BeamScanQueue(ScanQueue):
    """A turn's scans of a laser with a beam model, read and folded together (module
    docstring); the kinds of their readings are added to the robot's counts, their
    evidence to its grid (``sinks``: counts, evidence; ``readings_feature.py`` keeps
    them)."""

    def __init__(
        self,
        world: World,
        laser: Laser,
        shape_filter: QueryFilter,
        robot: MapHolder,
        rng: np.random.Generator,
        sinks: tuple[np.ndarray, np.ndarray],
    ) -> None:
        super().__init__(world, laser, shape_filter, robot)
        self.rng = rng
        self.counts, self.evidence = sinks

    def fold(self) -> Box | None:
        """Draw, cast, read and fold the held scans, in order (:class:`ScanQueue.fold`)."""
        if not self.poses:
            return None
        poses = np.array(self.poses, dtype=np.float64)
        self.poses.clear()
        laser, robot = self.laser, self.robot
        beam = laser.beam if laser.beam is not None else Beam()
        draws = self.rng.random((len(poses), laser.rays, DRAWS))
        grid, circles = self.world.ray_targets(self.shape_filter)
        r0, r1, c0, c1 = _cast_read_fold_many(
            grid, poses, ray_offsets(laser.fov_deg, laser.rays), float(laser.range), circles,
            robot.belief, robot.safe, float(laser.safe_fraction * laser.range),
            beam.params(laser.range), draws, self.counts, self.evidence,
        )  # fmt: skip
        return None if r0 < 0 else (r0, r1, c0, c1)
