"""Scans under drift (phase 5, sense then map): cast from the true pose, placed at the believed.

A robot's laser casts from where its body is (``Robot.position``, the truth). It folds
what it saw into its map where it believes it is: :func:`as_believed` moves the scan's
origin to the believed position and turns its rays (and the faces they hit) by the
heading error, so a drifted robot draws walls where they are not (ghost walls, smeared
rooms). With ``scan_matching`` among its corrections, every ``every``-th scan is first
aligned to the robot's own map (:func:`match_scan`, ``scan_match.py``) and the match
fused into its estimate as a measurement of the whole pose, with the covariance of the
match plus the window's grid (a uniform error over one step: ``step^2 / 12``).
"""

from __future__ import annotations

import math
from dataclasses import replace
from functools import cache

import numpy as np
from numba import njit

from mresim_phys.localization.feature import Localization
from mresim_phys.localization.scan_match import LiveField, Window, for_match, match
from mresim_phys.localization.spec import ScanMatchFix
from mresim_phys.types import BeliefGrid
from mresim_phys.world.space import Scan

MIN_POINTS = 20  # a scan with fewer wall hits is not matched: too little to pin a pose
MAX_POINTS = 30  # end points matched at most (every k-th hit)
TURN_STEP_DEG = 1.0  # the window's heading step


def as_believed(scan: Scan, loc: Localization) -> Scan:
    """``scan`` (cast from the true pose) as the robot places it: from its believed
    position, every ray and hit face turned by the heading error."""
    (tx, ty, tt), (bx, by, bt) = loc.true, loc.believed
    if (tx, ty, tt) == (bx, by, bt):
        return scan
    turn = bt - tt
    c, s = math.cos(turn), math.sin(turn)
    n = scan.normals
    normals = np.column_stack((c * n[:, 0] - s * n[:, 1], s * n[:, 0] + c * n[:, 1]))
    return replace(scan, origin=(bx, by), angles=scan.angles + turn, normals=normals)


def match_scan(loc: Localization, belief: BeliefGrid, scan: Scan) -> bool:
    """Align ``scan`` (true frame) to ``belief`` round the believed pose if this scan is
    due (``every``), and fuse the match into the estimate; True if it was fused."""
    fix = loc.matching
    if fix is None:
        return False
    loc.scans += 1
    if (loc.scans - 1) % fix.every:
        return False
    hits = np.flatnonzero(scan.wall_hit & (scan.ranges < scan.max_range))
    if len(hits) < MIN_POINTS:
        return False
    hits = hits[:: -(-len(hits) // MAX_POINTS)]  # every k-th: at most MAX_POINTS
    ranges, relative = scan.ranges[hits], scan.angles[hits] - loc.true[2]
    window = window_of(fix)
    if loc.live is None:
        loc.live = LiveField(belief.shape, fix.sigma)
    guess = loc.believed
    field = for_match(loc.live, belief, _reach(guess, ranges, relative, window))
    found = match(field, guess, ranges, relative, window)
    grid = np.diag([window.step**2 / 12, window.step**2 / 12, window.turn_step**2 / 12])
    loc.fix(loc.estimate.aligned(found.pose, found.cov + grid), "scan_matching")
    return True


@cache
def window_of(fix: ScanMatchFix) -> Window:
    """The poses ``fix`` tries round the believed pose."""
    return Window(fix.window, 0.25, math.radians(fix.turn_deg), math.radians(TURN_STEP_DEG))


def _reach(
    guess: tuple[float, float, float], ranges: np.ndarray, angles: np.ndarray, window: Window
) -> tuple[int, int, int, int]:
    """The box (row0, row1, col0, col1) the scan's end points reach from any pose of the
    window round ``guess``: their box at the guess, widened by the window's reach, the
    farthest point's sweep over the window's turn and two cells."""
    x0, y0, theta = guess
    box = _end_box(float(x0), float(y0), float(theta), ranges, angles)
    margin = window.reach + float(box[4]) * window.turn + 2.0
    return (int(box[2] - margin), int(box[3] + margin) + 1, int(box[0] - margin),
            int(box[1] + margin) + 1)  # fmt: skip


@njit(cache=True, nogil=True)
def _end_box(
    x0: float, y0: float, theta: float, ranges: np.ndarray, angles: np.ndarray
) -> np.ndarray:
    """(x min, x max, y min, y max, longest range) of the end points at a pose."""
    out = np.array([np.inf, -np.inf, np.inf, -np.inf, 0.0])
    for k in range(len(ranges)):
        x = x0 + ranges[k] * np.cos(theta + angles[k])
        y = y0 + ranges[k] * np.sin(theta + angles[k])
        out[0], out[1] = min(out[0], x), max(out[1], x)
        out[2], out[3] = min(out[2], y), max(out[3], y)
        out[4] = max(out[4], ranges[k])
    return out
