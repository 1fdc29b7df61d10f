"""Scan matching (``localization/scan_match.py``): a scan finds its pose in a room with
corners, and a long corridor leaves the pose along it open."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mresim_phys.localization import scan_match
from mresim_phys.localization.scan_match import Window, likelihood_field, match
from mresim_phys.types import FREE, OCCUPIED

ANGLES = np.radians(np.arange(-90.0, 91.0))  # 181 rays over 180 degrees, as the laser


def walled(rows: int, cols: int) -> np.ndarray:
    """A known room: FREE inside a one-cell wall."""
    belief = np.full((rows, cols), FREE, dtype=np.uint8)
    belief[0, :] = belief[-1, :] = belief[:, 0] = belief[:, -1] = OCCUPIED
    return belief


def scan_from(
    belief: np.ndarray, pose: tuple[float, float, float], reach: float
) -> tuple[np.ndarray, np.ndarray]:
    """Ranges and angles of the rays from ``pose`` that hit a wall within ``reach``
    (marched in 0.02-cell steps)."""
    ranges: list[float] = []
    angles: list[float] = []
    for angle in ANGLES:
        heading = pose[2] + angle
        for d in np.arange(0.0, reach, 0.02):
            x, y = pose[0] + d * math.cos(heading), pose[1] + d * math.sin(heading)
            if belief[int(y), int(x)] == OCCUPIED:
                ranges.append(float(d))
                angles.append(float(angle))
                break
    return np.array(ranges), np.array(angles)


def test_a_scan_in_a_room_with_corners_finds_its_pose() -> None:
    """A room with an inner wall; the guess is 1.5 cells and 0.05 rad off: the match
    lands within 0.3 cells and a step of heading of the true pose, and its spread stays
    within half a cell (the map's resolution: an end point anywhere in a wall cell
    scores alike)."""
    belief = walled(40, 60)
    belief[10:25, 30] = OCCUPIED
    belief[25, 30:45] = OCCUPIED
    truth = (20.3, 18.6, 0.4)
    ranges, angles = scan_from(belief, truth, 60.0)
    guess = (truth[0] + 1.5, truth[1] - 1.0, truth[2] - 0.05)
    found = match(likelihood_field(belief, 0.5), guess, ranges, angles, Window())
    assert math.dist(found.pose[:2], truth[:2]) <= 0.3
    assert abs(found.pose[2] - truth[2]) <= 0.03
    assert np.sqrt(np.linalg.eigvalsh(found.cov[:2, :2]).max()) < 0.5


def test_a_long_corridor_leaves_the_pose_along_it_open() -> None:
    """A 6-cell corridor 300 cells long, its ends beyond the laser's reach: across the
    corridor the match is sure, along it the pose distribution spreads over the window
    (the match cannot tell the right spot, and says so)."""
    belief = walled(8, 300)
    truth = (150.2, 4.1, 0.0)
    ranges, angles = scan_from(belief, truth, 40.0)
    guess = (truth[0] + 1.0, truth[1] + 0.5, truth[2])
    found = match(likelihood_field(belief, 0.5), guess, ranges, angles, Window())
    along, across = math.sqrt(found.cov[0, 0]), math.sqrt(found.cov[1, 1])
    assert abs(found.pose[1] - truth[1]) <= 0.3
    assert along > 1.0 and across < 0.3


def test_the_compiled_scores_are_the_sum_over_end_points_of_every_window_pose() -> None:
    """Every pose's score, against a plain numpy sum over its end points of the field
    interpolated between cell centres (off the map: the floor), on a random field and
    scan."""
    rng = np.random.default_rng(4)
    field = -rng.uniform(0, 4.5, (30, 40))
    ranges, angles = rng.uniform(0, 25, 50), rng.uniform(-1.5, 1.5, 50)
    guess = (20.2, 14.7, 0.3)
    for step in (0.5, 1.0):  # offsets within a cell, and whole cells (the coarse pass)
        window = Window(reach=2.0, step=step, turn=0.05, turn_step=0.05)
        scores = scan_match._scores(
            field, *guess, ranges, angles, window.offsets(), window.turns(), -4.5
        )
        for k, turn in enumerate(window.turns()):
            for i, dy in enumerate(window.offsets()):
                for j, dx in enumerate(window.offsets()):
                    heading = guess[2] + turn + angles
                    x = guess[0] + dx + ranges * np.cos(heading) - 0.5
                    y = guess[1] + dy + ranges * np.sin(heading) - 0.5
                    want = bilinear(field, x, y, -4.5).sum()
                    assert scores[k, i, j] == pytest.approx(want)


def bilinear(field: np.ndarray, x: np.ndarray, y: np.ndarray, floor: float) -> np.ndarray:
    """``field`` at points measured from the centre of cell (0, 0), interpolated between
    the four cell centres round each (off the map: ``floor``)."""
    c, r = np.floor(x).astype(int), np.floor(y).astype(int)
    fx, fy = x - c, y - r

    def at(rr: np.ndarray, cc: np.ndarray) -> np.ndarray:
        inside = (rr >= 0) & (rr < field.shape[0]) & (cc >= 0) & (cc < field.shape[1])
        out = np.full(rr.shape, floor)
        out[inside] = field[rr[inside], cc[inside]]
        return out

    return (
        at(r, c) * (1 - fx) * (1 - fy)
        + at(r, c + 1) * fx * (1 - fy)
        + at(r + 1, c) * (1 - fx) * fy
        + at(r + 1, c + 1) * fx * fy
    )
