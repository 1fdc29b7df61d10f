"""Pose estimate (phase 5, move; phase 6, communicate): a robot's believed pose and its uncertainty.

A robot's belief of its pose is a Gaussian: the mean ``(x, y, theta)`` its odometry and
corrections give, and a 3x3 covariance. Each motion grows the covariance by the
extended Kalman filter's prediction for the odometry motion model (Thrun, Burgard and
Fox, *Probabilistic Robotics*, 2005, sections 5.4 and 7.4):

    Sigma' = G Sigma G^T + V M V^T

with ``G`` the motion's Jacobian in the pose, ``V`` its Jacobian in the motion's parts
(rot1, trans, rot2) and ``M`` the diagonal of their noise variances
(``odometry.OdometryNoise.variances``). A measurement of the robot's position ``z`` with
covariance ``R`` (a known landmark: the base, a beacon) is fused by the Kalman update

    K = Sigma H^T (H Sigma H^T + R)^-1,  mu' = mu + K (z - H mu),
    Sigma' = (I - K H) Sigma (I - K H)^T + K R K^T

(``H`` picks the position out of the pose; the Joseph form keeps ``Sigma'`` symmetric
and positive semi-definite in floating point). A teammate seen on a link gives a range
``rho`` and a bearing ``beta`` (from the robot's heading) to the teammate's believed
position ``p_j``: the same update with

    h(mu) = (|p_j - p|, atan2(p_j - p) - theta),
    H = [[-dx / rho, -dy / rho, 0], [dy / rho^2, -dx / rho^2, -1]],
    R = diag(sigma_range^2, sigma_bearing^2) + J Sigma_j J^T

(``dx, dy = p_j - p``; ``J`` is ``h``'s Jacobian in ``p_j``: the teammate's own position
uncertainty ``Sigma_j`` weakens the fix; the bearing's residual is wrapped to [-pi, pi)).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from mresim_phys.localization.odometry import Motion, OdometryNoise, Pose, moved, wrap
from mresim_phys.types import FloatArray

POSITION = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])  # H of a position measurement


@dataclass(frozen=True)
class PoseEstimate:
    """A believed pose and its covariance (x, y in cells; theta in rad)."""

    mean: Pose
    cov: FloatArray

    @classmethod
    def certain(cls, pose: Pose) -> PoseEstimate:
        """A pose known exactly (a robot at its start)."""
        return cls(pose, np.zeros((3, 3)))

    def predicted(self, motion: Motion, noise: OdometryNoise) -> PoseEstimate:
        """The estimate after ``motion`` as the odometry reports it."""
        variances = np.array(noise.variances(motion))
        theta = self.mean[2] + motion.rot1
        cov = _predicted(self.cov, theta, motion.trans, variances)
        return PoseEstimate(moved(self.mean, motion), cov)

    def corrected(self, z: tuple[float, float], r: FloatArray) -> PoseEstimate:
        """The estimate after a measurement ``z`` of its position with covariance ``r``."""
        residual = np.array(z) - np.array(self.mean[:2])  # z - H mu
        return self._updated(POSITION, residual, r)

    def aligned(self, z: tuple[float, float, float], r: FloatArray) -> PoseEstimate:
        """The estimate after a measurement ``z`` of the whole pose with covariance ``r``
        (a scan match); the heading's residual wrapped to [-pi, pi)."""
        mu = self.mean
        residual = np.array([z[0] - mu[0], z[1] - mu[1], wrap(z[2] - mu[2])])
        return self._updated(np.eye(3), residual, r)

    def ranged(
        self, other: PoseEstimate, z: tuple[float, float], sigma_range: float,
        sigma_bearing: float,
    ) -> PoseEstimate:  # fmt: skip
        """The estimate after seeing teammate ``other`` (its believed pose and covariance)
        at range and bearing ``z``."""
        dx, dy = other.mean[0] - self.mean[0], other.mean[1] - self.mean[1]
        rho2 = max(dx * dx + dy * dy, 1e-12)
        rho = math.sqrt(rho2)
        h = np.array([[-dx / rho, -dy / rho, 0.0], [dy / rho2, -dx / rho2, -1.0]])
        j = -h[:, :2]  # the same geometry seen from the teammate's position
        spread = product(product(j, np.ascontiguousarray(other.cov[:2, :2])), j.T)
        r = np.diag([sigma_range**2, sigma_bearing**2]) + spread
        predicted = (rho, math.atan2(dy, dx) - self.mean[2])
        residual = np.array([z[0] - predicted[0], wrap(z[1] - predicted[1])])
        return self._updated(h, residual, r)

    def _updated(self, h: FloatArray, residual: FloatArray, r: FloatArray) -> PoseEstimate:
        """The Kalman update for a measurement with Jacobian ``h``, ``residual`` and
        noise ``r`` (Joseph form)."""
        mu, cov = _kalman(np.array(self.mean), self.cov, h, residual, r)
        return PoseEstimate((float(mu[0]), float(mu[1]), wrap(float(mu[2]))), cov)

    def position_sigma(self) -> float:
        """The position's standard deviation along its worst axis (cells)."""
        return math.sqrt(max(float(np.linalg.eigvalsh(self.cov[:2, :2]).max()), 0.0))


@njit(cache=True, nogil=True)
def _predicted(cov: FloatArray, theta: float, t: float, variances: FloatArray) -> FloatArray:
    """``G cov G^T + V M V^T`` of :meth:`PoseEstimate.predicted` (``theta``: the heading
    after the first turn, ``t`` the translation), compiled: it runs at every leg."""
    c, s = np.cos(theta), np.sin(theta)
    g = np.array([[1.0, 0.0, -t * s], [0.0, 1.0, t * c], [0.0, 0.0, 1.0]])
    v = np.array([[-t * s, c, 0.0], [t * c, s, 0.0], [1.0, 0.0, 1.0]])
    out: FloatArray = product(product(g, cov), g.T) + product(v * variances, v.T)
    return symmetric(out)


@njit(cache=True, nogil=True)
def _kalman(
    mu: FloatArray, cov: FloatArray, h: FloatArray, residual: FloatArray, r: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """The Kalman update of :meth:`PoseEstimate._updated` (Joseph form), compiled: a
    correction is fused after every scan of a robot that matches its scans."""
    gain = product(product(cov, h.T), inverse(product(product(h, cov), h.T) + r))
    keep = np.eye(3) - product(gain, h)
    out = product(product(keep, cov), keep.T) + product(product(gain, r), gain.T)
    return mu + product(gain, residual.reshape(-1, 1))[:, 0], symmetric(out)


@njit(cache=True, nogil=True)
def product(a: FloatArray, b: FloatArray) -> FloatArray:
    """The matrix product ``a @ b``, each entry summed in order of ``k``: the same floats on
    every processor. ``@`` and ``np.linalg`` call the BLAS, whose kernels differ by
    processor (on an AMD EPYC with AVX-512 a run of scenario 29 differed in a heading
    error from the same run on a processor the BLAS served with its Haswell kernels)."""
    n, m, p = a.shape[0], a.shape[1], b.shape[1]
    out = np.zeros((n, p))
    for i in range(n):
        for j in range(p):
            total = 0.0
            for k in range(m):
                total += a[i, k] * b[k, j]
            out[i, j] = total
    return out


@njit(cache=True, nogil=True)
def inverse(a: FloatArray) -> FloatArray:
    """The inverse of the small square matrix ``a`` by Gauss-Jordan elimination with
    partial pivoting (the first largest pivot): the same floats on every processor."""
    n = a.shape[0]
    work, out = a.copy(), np.eye(n)
    for col in range(n):
        pivot = col
        for row in range(col + 1, n):
            if abs(work[row, col]) > abs(work[pivot, col]):
                pivot = row
        for k in range(n):
            work[col, k], work[pivot, k] = work[pivot, k], work[col, k]
            out[col, k], out[pivot, k] = out[pivot, k], out[col, k]
        scale = work[col, col]
        for k in range(n):
            work[col, k] /= scale
            out[col, k] /= scale
        for row in range(n):
            if row != col:
                factor = work[row, col]
                for k in range(n):
                    work[row, k] -= factor * work[col, k]
                    out[row, k] -= factor * out[col, k]
    return out


@njit(cache=True, nogil=True)
def symmetric(cov: FloatArray) -> FloatArray:
    """``cov`` made exactly symmetric (floating point drifts it)."""
    out: FloatArray = (cov + cov.T) / 2.0
    return out
