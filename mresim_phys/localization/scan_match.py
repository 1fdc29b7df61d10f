"""Scan matching (phase 2, sense): where a scan fits a robot's own map best, and how surely.

A correlative scan matcher (E. Olson, "Real-time correlative scan matching", ICRA 2009).
The map's known walls become a likelihood field: a scan end point at distance ``d`` from
the nearest wall cell centre scores ``-d^2 / (2 sigma^2)``, capped at ``MAX_DISTANCE``
sigmas (an end point far from every wall, or off the map, costs the same bounded
amount). Every pose of a window round the believed pose (a grid of position offsets and
of headings) scores the sum over the scan's end points; the pose distribution is
``p ~ exp(score)``. The match is the best pose, and its covariance is the covariance of
that distribution over the window (Olson's estimate): small where the scan pins the
pose down, large along a direction the map cannot tell apart (a long featureless
corridor), which is how a caller sees that the match failed there. The window's scores
are one compiled pass (``_scores``, numba): 1.7 ms for 181 rays over the default window's
5,625 poses (numpy: 7.7 ms).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit
from scipy.ndimage import distance_transform_edt

from mresim_phys.localization.odometry import Pose
from mresim_phys.types import OCCUPIED, BeliefGrid, FloatArray

MAX_DISTANCE = 3.0  # sigmas: an end point farther from every wall scores as if this far


@dataclass(frozen=True)
class Window:
    """The poses tried round a guess: offsets up to ``reach`` cells in steps of ``step``,
    headings up to ``turn`` rad in steps of ``turn_step``."""

    reach: float = 3.0
    step: float = 0.25
    turn: float = 0.1
    turn_step: float = 0.025

    def offsets(self) -> FloatArray:
        """The position offsets along one axis."""
        count = round(self.reach / self.step)
        out: FloatArray = np.arange(-count, count + 1, dtype=np.float64) * self.step
        return out

    def turns(self) -> FloatArray:
        """The heading offsets."""
        count = round(self.turn / self.turn_step)
        out: FloatArray = np.arange(-count, count + 1, dtype=np.float64) * self.turn_step
        return out


@dataclass(frozen=True)
class Match:
    """The best pose of the window, the covariance of the pose distribution over it, and
    the best score per end point (0: every end point on a wall)."""

    pose: Pose
    cov: FloatArray
    score: float


def likelihood_field(belief: BeliefGrid, sigma: float) -> FloatArray:
    """Per cell: the log-likelihood of a scan end point there (module docstring)."""
    walls = belief == OCCUPIED
    if not walls.any():
        return np.full(belief.shape, -(MAX_DISTANCE**2) / 2.0)
    distance = distance_transform_edt(~walls) / sigma
    out: FloatArray = -(np.minimum(distance, MAX_DISTANCE) ** 2) / 2.0
    return out


def match(
    field: FloatArray, guess: Pose, ranges: FloatArray, angles: FloatArray, window: Window
) -> Match:
    """Match a scan (``ranges`` of its hits, at ``angles`` relative to the heading; cells
    and rad) taken from about ``guess`` against a map's ``field``."""
    offsets, turns = window.offsets(), window.turns()
    scores = _scores(
        np.ascontiguousarray(field, dtype=np.float64), float(guess[0]), float(guess[1]),
        float(guess[2]), np.asarray(ranges, dtype=np.float64),
        np.asarray(angles, dtype=np.float64), offsets, turns, -(MAX_DISTANCE**2) / 2.0,
    )  # fmt: skip
    return _summary(scores, offsets, turns, guess, len(ranges))


@njit(cache=True, nogil=True)
def _scores(
    field: FloatArray, x0: float, y0: float, theta: float, ranges: FloatArray,
    angles: FloatArray, offsets: FloatArray, turns: FloatArray, floor: float,
) -> FloatArray:  # fmt: skip
    """The score of every pose of the window: (turn, y offset, x offset)."""
    rows, cols = field.shape
    n, m = len(ranges), len(offsets)
    out = np.zeros((len(turns), m, m))
    xs, ys = np.empty(n), np.empty(n)
    for k in range(len(turns)):
        for p in range(n):
            heading = theta + turns[k] + angles[p]
            xs[p] = x0 + ranges[p] * np.cos(heading)
            ys[p] = y0 + ranges[p] * np.sin(heading)
        for i in range(m):
            for j in range(m):
                total = 0.0
                for p in range(n):
                    c = int(np.floor(xs[p] + offsets[j]))
                    r = int(np.floor(ys[p] + offsets[i]))
                    if 0 <= r < rows and 0 <= c < cols:
                        total += field[r, c]
                    else:
                        total += floor
                out[k, i, j] = total
    return out


def _summary(
    scores: FloatArray, offsets: FloatArray, turns: FloatArray, guess: Pose, points: int
) -> Match:
    """The best pose and the covariance of ``p ~ exp(score)`` over the window."""
    k, i, j = np.unravel_index(int(np.argmax(scores)), scores.shape)
    weights = np.exp(scores - scores[k, i, j])
    weights /= weights.sum()
    t, y, x = np.meshgrid(turns, offsets, offsets, indexing="ij")
    samples = np.stack([x.ravel(), y.ravel(), t.ravel()])  # (3, m)
    w = weights.ravel()
    mean = samples @ w
    centred = samples - mean[:, None]
    cov = (centred * w) @ centred.T
    best = (guess[0] + float(offsets[j]), guess[1] + float(offsets[i]), guess[2] + float(turns[k]))
    return Match(best, cov, float(scores[k, i, j]) / max(points, 1))
