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
from functools import cache

import numpy as np
from numba import njit
from scipy.ndimage import distance_transform_edt

from mresim_phys.localization.odometry import Pose
from mresim_phys.types import OCCUPIED, BeliefGrid, FloatArray, IntArray

MAX_DISTANCE = 3.0  # sigmas: an end point farther from every wall scores as if this far
COARSE = 4  # the first pass's position step: this many times the window's
REFRESH_EVERY = 4  # for_match: a robot's matches between refreshes of its field
SLACK = 8  # cells round a match's box that a refresh makes exact too
COARSE_TURN = 3  # and its heading step
NUDGE = 0.5  # cells along a ray: its end point inside the wall cell it hit, not on its face


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


class LiveField:
    """A robot's likelihood field kept up to date with its map where a match needs it.

    The field of a cell depends only on the walls within ``MAX_DISTANCE`` sigmas of it, so
    :meth:`refresh` compares the map's walls with those the field was made from over a
    box (the box a scan's end points can reach, widened by that radius), and recomputes
    only the cells near a wall that appeared or went (``_recompute``, numba): the same
    values :func:`likelihood_field` gives over the box, for a few cells' work a scan.
    """

    def __init__(self, shape: tuple[int, int], sigma: float) -> None:
        self.sigma = sigma
        self.radius = int(np.ceil(MAX_DISTANCE * sigma))
        self.field = np.full(shape, -(MAX_DISTANCE**2) / 2.0)
        self.walls = np.zeros(shape, dtype=np.bool_)  # the walls the field was made from
        self.box: tuple[int, int, int, int] | None = None  # where a match last made it exact
        self.age = 0  # matches since

    def refresh(self, belief: BeliefGrid, box: tuple[int, int, int, int]) -> FloatArray:
        """The field, exact over ``box`` (row0, row1, col0, col1) for ``belief`` now: the
        walls that changed within ``box`` widened by the radius are found (numpy), and the
        cells within the radius of one computed again (``_recompute``)."""
        rows, cols = belief.shape
        pad = self.radius
        r0, r1 = max(box[0] - pad, 0), min(box[1] + pad, rows)
        c0, c1 = max(box[2] - pad, 0), min(box[3] + pad, cols)
        if r0 >= r1 or c0 >= c1:
            return self.field
        now = belief[r0:r1, c0:c1] == OCCUPIED
        changed = np.flatnonzero(now != self.walls[r0:r1, c0:c1])
        if len(changed):
            self.walls[r0:r1, c0:c1] = now
            at_rows, at_cols = np.divmod(changed, c1 - c0)
            added = now.ravel()[changed]
            _recompute(
                belief, self.field, at_rows + r0, at_cols + c0, added, pad,
                float(self.sigma), float(MAX_DISTANCE),
            )  # fmt: skip
        return self.field


def for_match(live: LiveField, belief: BeliefGrid, box: tuple[int, int, int, int]) -> FloatArray:
    """The field a match over ``box`` reads: made exact over ``box`` widened by ``SLACK``
    cells at every ``REFRESH_EVERY``-th match of the robot, or as soon as ``box`` leaves
    the box it was last made exact over. In between, the walls its last few scans added
    may be missing from it (a wall just seen at the frontier: the next scans' end points
    on it score as if far from any wall, a bounded cost)."""
    live.age += 1
    last = live.box
    if live.age < REFRESH_EVERY and last is not None and _within(box, last):
        return live.field
    wide = (box[0] - SLACK, box[1] + SLACK, box[2] - SLACK, box[3] + SLACK)
    live.box, live.age = wide, 0
    return live.refresh(belief, wide)


def _within(box: tuple[int, int, int, int], outer: tuple[int, int, int, int]) -> bool:
    """Whether ``box`` lies inside ``outer`` (both row0, row1, col0, col1)."""
    return outer[0] <= box[0] and box[1] <= outer[1] and outer[2] <= box[2] and box[3] <= outer[3]


@njit(cache=True, nogil=True)
def _recompute(
    belief: BeliefGrid, field: FloatArray, at_rows: IntArray, at_cols: IntArray,
    added: np.ndarray, radius: int, sigma: float, cap: float,
) -> None:  # fmt: skip
    """The field after walls changed at (``at_rows``, ``at_cols``): a wall that appeared
    raises the field round it (each cell keeps its nearest wall); round a wall that went,
    every cell is computed again from the walls within ``radius`` of it."""
    rows, cols = belief.shape
    scale = 1.0 / (2.0 * sigma * sigma)
    gone = 0
    for k in range(len(at_rows)):
        if not added[k]:
            gone += 1
            continue
        r, c = at_rows[k], at_cols[k]
        for rr in range(max(r - radius, 0), min(r + radius + 1, rows)):
            for cc in range(max(c - radius, 0), min(c + radius + 1, cols)):
                value = -min(((rr - r) ** 2 + (cc - c) ** 2) * scale, cap * cap / 2.0)
                if value > field[rr, cc]:
                    field[rr, cc] = value
    if gone:
        _recompute_round_gone(belief, field, at_rows, at_cols, added, radius, scale, cap)


@njit(cache=True, nogil=True)
def _recompute_round_gone(
    belief: BeliefGrid, field: FloatArray, at_rows: IntArray, at_cols: IntArray,
    added: np.ndarray, radius: int, scale: float, cap: float,
) -> None:  # fmt: skip
    """Every cell within ``radius`` of a wall that went, computed again."""
    rows, cols = belief.shape
    for k in range(len(at_rows)):
        if added[k]:
            continue
        r, c = at_rows[k], at_cols[k]
        for i in range(max(r - radius, 0), min(r + radius + 1, rows)):
            for j in range(max(c - radius, 0), min(c + radius + 1, cols)):
                best = cap * cap / 2.0
                for rr in range(max(i - radius, 0), min(i + radius + 1, rows)):
                    for cc in range(max(j - radius, 0), min(j + radius + 1, cols)):
                        if belief[rr, cc] == OCCUPIED:
                            best = min(best, ((rr - i) ** 2 + (cc - j) ** 2) * scale)
                field[i, j] = -best


def match(
    field: FloatArray, guess: Pose, ranges: FloatArray, angles: FloatArray, window: Window
) -> Match:
    """Match a scan (``ranges`` of its hits, at ``angles`` relative to the heading; cells
    and rad; each end point taken ``NUDGE`` beyond its hit, into the wall cell) taken
    from about ``guess`` against a map's ``field``: the whole window at ``COARSE`` times
    its position step and ``COARSE_TURN`` times its heading step, then the window's own
    steps round the best coarse pose (half a coarse step either side; the pose is that
    distribution's mean). The covariance is the fine distribution's plus the coarse
    one's where that spreads over more than a coarse step (a corridor's ambiguity, not
    the coarse grid's own). One compiled call (``_two_passes``)."""
    coarse = Window(window.reach, window.step * COARSE, window.turn, window.turn_step * COARSE_TURN)
    if coarse.step > window.reach or coarse.turn_step > window.turn:
        coarse = window  # a window too small for two passes: one
    fine = Window(coarse.step / 2, window.step, coarse.turn_step / 2, window.turn_step)
    pose, cov, score = _two_passes(
        np.ascontiguousarray(field, dtype=np.float64),
        np.array(guess, dtype=np.float64),
        np.asarray(ranges, dtype=np.float64) + NUDGE,
        np.asarray(angles, dtype=np.float64),
        *_axes(coarse), *_axes(fine), coarse is not window,
        np.array([coarse.step**2, coarse.turn_step**2]), -(MAX_DISTANCE**2) / 2.0,
    )  # fmt: skip
    return Match((float(pose[0]), float(pose[1]), float(pose[2])), cov, score / max(len(ranges), 1))


@cache
def _axes(window: Window) -> tuple[FloatArray, FloatArray]:
    """The window's position offsets and heading offsets (made once per window)."""
    return window.offsets(), window.turns()


@njit(cache=True, nogil=True)
def _two_passes(
    field: FloatArray, guess: FloatArray, ranges: FloatArray, angles: FloatArray,
    coarse_offsets: FloatArray, coarse_turns: FloatArray, fine_offsets: FloatArray,
    fine_turns: FloatArray, refine: bool, spread: FloatArray, floor: float,
) -> tuple[FloatArray, FloatArray, float]:  # fmt: skip
    """The kernel of :func:`match`: (pose, covariance, best score). Not ``refine``: the
    coarse pass alone, its best pose and covariance."""
    scores = _scores(field, guess[0], guess[1], guess[2], ranges, angles, coarse_offsets,
                     coarse_turns, floor)  # fmt: skip
    best, _, rough = _moments(scores, coarse_offsets, coarse_turns)
    if not refine:
        return guess + best, rough, scores.max()
    centre = guess + best
    scores = _scores(field, centre[0], centre[1], centre[2], ranges, angles, fine_offsets,
                     fine_turns, floor)  # fmt: skip
    _, mean, cov = _moments(scores, fine_offsets, fine_turns)
    values, vectors = _eigh2(rough[0, 0], rough[0, 1], rough[1, 1])  # the coarse spread
    for a in range(2):  # beyond its grid
        if values[a] > spread[0]:
            cov[:2, :2] += values[a] * np.outer(vectors[:, a], vectors[:, a])
    if rough[2, 2] > spread[1]:
        cov[2, 2] += rough[2, 2]
    return centre + mean, cov, scores.max()


@njit(cache=True, nogil=True)
def _eigh2(a: float, b: float, c: float) -> tuple[FloatArray, FloatArray]:
    """Eigenvalues (ascending) and unit eigenvectors (columns) of the symmetric matrix
    [[a, b], [b, c]], in closed form: the same bits on every CPU, where LAPACK's ``eigh``
    differs in the last bits between CPUs (its kernels are chosen per CPU), which moved a
    scan-matching run's pose errors between machines."""
    half, mid = 0.5 * (a - c), 0.5 * (a + c)
    root = np.sqrt(half * half + b * b)
    values = np.array([mid - root, mid + root])
    vectors = np.eye(2)
    if b != 0.0:
        for k in range(2):
            x, y = values[k] - c, b
            norm = np.sqrt(x * x + y * y)
            vectors[0, k], vectors[1, k] = x / norm, y / norm
    elif a > c:  # diagonal: the larger value belongs to the first axis
        vectors[0, 0], vectors[1, 0], vectors[0, 1], vectors[1, 1] = 0.0, 1.0, 1.0, 0.0
    return values, vectors


@njit(cache=True, nogil=True)
def _scores(
    field: FloatArray, x0: float, y0: float, theta: float, ranges: FloatArray,
    angles: FloatArray, offsets: FloatArray, turns: FloatArray, floor: float,
) -> FloatArray:  # fmt: skip
    """The score of every pose of the window: (turn, y offset, x offset). An end point
    scores the field interpolated bilinearly between the centres of the four cells round
    it (:func:`_at`): a pose a quarter cell off scores below the right one, where the
    cell it falls in alone would score the same (a plateau a cell wide)."""
    n, m = len(ranges), len(offsets)
    out = np.zeros((len(turns), m, m))
    xs, ys = np.empty(n), np.empty(n)
    whole = True  # whole-cell offsets: a point's weights are the same at every offset
    for j in range(m):
        whole = whole and offsets[j] == np.floor(offsets[j])
    for k in range(len(turns)):
        for p in range(n):
            heading = theta + turns[k] + angles[p]
            xs[p] = x0 + ranges[p] * np.cos(heading) - 0.5  # from cell centres
            ys[p] = y0 + ranges[p] * np.sin(heading) - 0.5
        if whole:
            _whole_offsets(field, xs, ys, offsets, floor, out[k])
            continue
        for i in range(m):
            for j in range(m):
                total = 0.0
                for p in range(n):
                    total += _at(field, xs[p] + offsets[j], ys[p] + offsets[i], floor)
                out[k, i, j] = total
    return out


@njit(cache=True, nogil=True)
def _whole_offsets(
    field: FloatArray, xs: FloatArray, ys: FloatArray, offsets: FloatArray, floor: float,
    out: FloatArray,
) -> None:  # fmt: skip
    """:func:`_scores` of one heading for whole-cell ``offsets``: each end point's four
    cells and weights found once, then read at every offset (the same sums)."""
    rows, cols = field.shape
    for p in range(len(xs)):
        c, r = int(np.floor(xs[p])), int(np.floor(ys[p]))
        fx, fy = xs[p] - c, ys[p] - r
        w00, w01 = (1.0 - fx) * (1.0 - fy), fx * (1.0 - fy)
        w10, w11 = (1.0 - fx) * fy, fx * fy
        for i in range(len(offsets)):
            rr = r + int(offsets[i])
            for j in range(len(offsets)):
                cc = c + int(offsets[j])
                if rr >= 0 and rr + 1 < rows and cc >= 0 and cc + 1 < cols:
                    value = (field[rr, cc] * w00 + field[rr, cc + 1] * w01
                             + field[rr + 1, cc] * w10 + field[rr + 1, cc + 1] * w11)  # fmt: skip
                else:
                    value = _at(field, xs[p] + offsets[j], ys[p] + offsets[i], floor)
                out[i, j] += value


@njit(cache=True, nogil=True, inline="always")
def _at(field: FloatArray, x: float, y: float, floor: float) -> float:
    """``field`` at (``x``, ``y``) measured from the centre of cell (0, 0), bilinear; a
    cell off the map counts as ``floor``."""
    rows, cols = field.shape
    c, r = int(np.floor(x)), int(np.floor(y))
    fx, fy = x - c, y - r
    total = 0.0
    for dr in range(2):
        for dc in range(2):
            rr, cc = r + dr, c + dc
            value = field[rr, cc] if 0 <= rr < rows and 0 <= cc < cols else floor
            total += value * (fx if dc else 1.0 - fx) * (fy if dr else 1.0 - fy)
    return total


@njit(cache=True, nogil=True)
def _moments(
    scores: FloatArray, offsets: FloatArray, turns: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The best offset (x, y, turn), and the mean and covariance of ``p ~ exp(score)``
    over the window."""
    flat = np.argmax(scores)
    k, rest = divmod(flat, scores.shape[1] * scores.shape[2])
    i, j = divmod(rest, scores.shape[2])
    top = scores[k, i, j]
    best = np.array([offsets[j], offsets[i], turns[k]])
    total, mean, second = 0.0, np.zeros(3), np.zeros((3, 3))
    v = np.empty(3)
    for k in range(scores.shape[0]):
        for i in range(scores.shape[1]):
            for j in range(scores.shape[2]):
                w = np.exp(scores[k, i, j] - top)
                v[0], v[1], v[2] = offsets[j], offsets[i], turns[k]
                total += w
                for a in range(3):
                    mean[a] += w * v[a]
                    for b in range(3):
                        second[a, b] += w * v[a] * v[b]
    mean /= total
    cov = second / total - np.outer(mean, mean)
    return best, mean, (cov + cov.T) / 2.0
