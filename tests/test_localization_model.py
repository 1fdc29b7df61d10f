"""The odometry motion model and the pose estimate (``mresim_phys/localization``):
exact with zero noise, drift with the model's variance, corrections that shrink it."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from mresim_phys.localization.estimate import PoseEstimate
from mresim_phys.localization.odometry import (
    Motion,
    OdometryNoise,
    executed,
    motion_between,
    moved,
    wrap,
)

NOISE = OdometryNoise(0.02, 0.001, 0.02, 0.01)


@pytest.mark.parametrize(
    ("start", "end"),
    [
        ((0.0, 0.0, 0.0), (3.0, 4.0, 1.0)),
        ((5.5, 2.5, -3.0), (1.0, 1.0, 3.0)),
        ((2.0, 2.0, 0.5), (2.0, 2.0, -2.5)),
    ],
)
def test_a_motion_taken_apart_and_done_again_ends_where_it_should(
    start: tuple[float, float, float], end: tuple[float, float, float]
) -> None:
    x, y, theta = moved(start, motion_between(start, end))
    assert (x, y) == pytest.approx(end[:2]) and wrap(theta - end[2]) == pytest.approx(0.0)


def test_zero_noise_executes_every_motion_exactly() -> None:
    rng = np.random.default_rng(1)
    exact = OdometryNoise(0.0, 0.0, 0.0, 0.0)
    for _ in range(100):
        motion = Motion(*rng.uniform(-3, 3, 3))
        assert executed(motion, exact, rng) == motion


def test_the_drift_of_many_motions_has_the_model_s_variance() -> None:
    """10,000 executions of one motion: each part's noise has the variance the model
    gives it (within 5 %), the poses they end at spread as the filter predicts, and their
    mean falls short of the noise-free end as a Gaussian heading error makes it
    (E[cos(a + e)] = cos(a) exp(-var / 2))."""
    rng = np.random.default_rng(7)
    motion = Motion(0.4, 6.0, -0.3)
    runs = [executed(motion, NOISE, rng) for _ in range(10_000)]
    parts = np.array([[m.rot1, m.trans, m.rot2] for m in runs])
    spread = parts.var(axis=0)
    assert spread == pytest.approx(NOISE.variances(motion), rel=0.05)
    start = (1.0, 2.0, 0.3)
    ends = np.array([moved(start, m) for m in runs])
    predicted = PoseEstimate.certain(start).predicted(motion, NOISE)
    assert np.cov(ends[:, :2].T) == pytest.approx(predicted.cov[:2, :2], rel=0.1, abs=1e-3)
    heading, shrink = start[2] + motion.rot1, math.exp(-NOISE.variances(motion)[0] / 2)
    mean = (start[0] + motion.trans * math.cos(heading) * shrink,
            start[1] + motion.trans * math.sin(heading) * shrink)  # fmt: skip
    assert ends[:, :2].mean(axis=0) == pytest.approx(mean, abs=0.03)


def test_uncertainty_grows_with_every_motion() -> None:
    estimate = PoseEstimate.certain((0.0, 0.0, 0.0))
    sigmas = []
    for _ in range(20):
        estimate = estimate.predicted(Motion(0.1, 5.0, 0.0), NOISE)
        sigmas.append(estimate.position_sigma())
    assert all(b > a for a, b in itertools.pairwise(sigmas))
    assert np.all(np.linalg.eigvalsh(estimate.cov) >= 0)


def test_fixes_of_a_known_landmark_pull_the_error_down_to_their_noise() -> None:
    """A robot 200 motions out (metres of drift) takes position fixes of sigma 0.5 cells:
    its error falls to about that noise and its uncertainty below it."""
    rng = np.random.default_rng(3)
    truth, belief = (0.0, 0.0, 0.0), PoseEstimate.certain((0.0, 0.0, 0.0))
    for _ in range(200):
        motion = Motion(0.05, 4.0, -0.05)
        truth = moved(truth, executed(motion, NOISE, rng))
        belief = belief.predicted(motion, NOISE)
    before = math.dist(truth[:2], belief.mean[:2])
    sigma, r = 0.5, np.eye(2) * 0.25
    for _ in range(10):
        z = (truth[0] + rng.normal(0, sigma), truth[1] + rng.normal(0, sigma))
        belief = belief.corrected(z, r)
    after = math.dist(truth[:2], belief.mean[:2])
    assert before > 5 * sigma and after < 2 * sigma
    assert belief.position_sigma() < sigma


@pytest.mark.parametrize("bad", [-0.1, math.nan, math.inf])
def test_a_noise_parameter_below_zero_or_not_finite_is_refused(bad: float) -> None:
    with pytest.raises(ValueError, match="odometry noise a2 must be a finite number >= 0"):
        OdometryNoise(0.0, bad, 0.0, 0.0)


def seen_from(
    pose: tuple[float, float, float], other: tuple[float, float], rng: np.random.Generator,
    sigma_range: float, sigma_bearing: float,
) -> tuple[float, float]:  # fmt: skip
    """A noisy range and bearing from ``pose`` to the point ``other``."""
    dx, dy = other[0] - pose[0], other[1] - pose[1]
    bearing = wrap(math.atan2(dy, dx) - pose[2] + rng.normal(0, sigma_bearing))
    return math.hypot(dx, dy) + rng.normal(0, sigma_range), bearing


def test_a_teammate_seen_on_a_link_pulls_a_lost_robot_back() -> None:
    """A robot whose belief is 4 cells and 0.2 rad off (and says so) sees a teammate that
    knows where it is, from changing angles as it turns: the error falls under a cell,
    the heading's under 0.05 rad. A teammate as unsure as the robot helps less."""
    rng = np.random.default_rng(5)
    truth = (50.0, 40.0, 0.3)
    off = PoseEstimate((53.0, 37.5, 0.5), np.diag([9.0, 9.0, 0.05]))
    sure = PoseEstimate.certain((62.0, 45.0, 0.0))
    vague = PoseEstimate((62.0, 45.0, 0.0), np.diag([9.0, 9.0, 0.05]))
    by_sure, by_vague = off, off
    for k in range(10):
        z = seen_from(truth, sure.mean[:2], rng, 0.3, math.radians(2))
        by_sure = by_sure.ranged(sure, z, 0.3, math.radians(2))
        by_vague = by_vague.ranged(vague, z, 0.3, math.radians(2))
        sure = PoseEstimate.certain((62.0 - 2 * k, 45.0 + 3 * k, 0.0))  # it drives on
        vague = PoseEstimate(sure.mean, vague.cov)
    assert math.dist(by_sure.mean[:2], truth[:2]) < 1.0
    assert abs(wrap(by_sure.mean[2] - truth[2])) < 0.05
    assert by_sure.position_sigma() < by_vague.position_sigma() < off.position_sigma()


def test_the_closed_form_2x2_eigen_decomposition_rebuilds_its_matrix() -> None:
    """Scan matching's spread (``scan_match._eigh2``): LAPACK's values and projections, in
    arithmetic that gives the same bits on every CPU."""
    from mresim_phys.localization.scan_match import _eigh2

    rng = np.random.default_rng(0)
    for k in range(300):
        half = rng.normal(size=(2, 2))
        m = half @ half.T
        if k % 5 == 0:
            m[0, 1] = m[1, 0] = 0.0
        values, vectors = _eigh2(m[0, 0], m[0, 1], m[1, 1])
        expected, columns = np.linalg.eigh(m)
        assert values == pytest.approx(expected, abs=1e-12)
        assert np.allclose(vectors @ np.diag(values) @ vectors.T, m)
        for a in range(2):
            projection = np.outer(vectors[:, a], vectors[:, a])
            assert np.allclose(projection, np.outer(columns[:, a], columns[:, a]), atol=1e-8)


def test_the_filters_products_and_inverses_are_the_same_floats_on_every_processor() -> None:
    """The filter's matrix products sum each entry in order (plain float operations, no
    BLAS kernel chosen by processor), and its inverse inverts."""
    from mresim_phys.localization.estimate import inverse, product

    rng = np.random.default_rng(7)
    for n, m, p in [(3, 3, 3), (2, 3, 2), (3, 2, 1)]:
        a, b = rng.normal(size=(n, m)), rng.normal(size=(m, p))
        expected = [[0.0] * p for _ in range(n)]
        for i in range(n):
            for j in range(p):
                total = 0.0
                for k in range(m):
                    total += float(a[i, k]) * float(b[k, j])
                expected[i][j] = total
        assert product(a, b).tobytes() == np.array(expected).tobytes()
        assert product(a.T.copy().T, b).tobytes() == product(a, b).tobytes()  # any layout
    for n in (2, 3):
        half = rng.normal(size=(n, n))
        spd = half @ half.T + n * np.eye(n)
        np.testing.assert_allclose(product(spd, inverse(spd)), np.eye(n), atol=1e-12)
