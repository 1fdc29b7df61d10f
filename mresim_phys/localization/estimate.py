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
and positive semi-definite in floating point).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mresim_phys.localization.odometry import Motion, OdometryNoise, Pose, moved, wrap

Matrix = NDArray[np.float64]
POSITION = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])  # H of a position measurement


@dataclass(frozen=True)
class PoseEstimate:
    """A believed pose and its covariance (x, y in cells; theta in rad)."""

    mean: Pose
    cov: Matrix

    @classmethod
    def certain(cls, pose: Pose) -> PoseEstimate:
        """A pose known exactly (a robot at its start)."""
        return cls(pose, np.zeros((3, 3)))

    def predicted(self, motion: Motion, noise: OdometryNoise) -> PoseEstimate:
        """The estimate after ``motion`` as the odometry reports it."""
        theta = self.mean[2] + motion.rot1
        c, s, t = math.cos(theta), math.sin(theta), motion.trans
        g = np.array([[1.0, 0.0, -t * s], [0.0, 1.0, t * c], [0.0, 0.0, 1.0]])
        v = np.array([[-t * s, c, 0.0], [t * c, s, 0.0], [1.0, 0.0, 1.0]])
        m = np.diag(noise.variances(motion))
        cov = g @ self.cov @ g.T + v @ m @ v.T
        return PoseEstimate(moved(self.mean, motion), symmetric(cov))

    def corrected(self, z: tuple[float, float], r: Matrix) -> PoseEstimate:
        """The estimate after a measurement ``z`` of its position with covariance ``r``."""
        h, cov = POSITION, self.cov
        gain = cov @ h.T @ np.linalg.inv(h @ cov @ h.T + r)
        mu = np.array(self.mean)
        mu = mu + gain @ (np.array(z) - h @ mu)
        keep = np.eye(3) - gain @ h
        cov = keep @ cov @ keep.T + gain @ r @ gain.T
        return PoseEstimate((float(mu[0]), float(mu[1]), wrap(float(mu[2]))), symmetric(cov))

    def position_sigma(self) -> float:
        """The position's standard deviation along its worst axis (cells)."""
        return math.sqrt(max(float(np.linalg.eigvalsh(self.cov[:2, :2]).max()), 0.0))


def symmetric(cov: Matrix) -> Matrix:
    """``cov`` made exactly symmetric (floating point drifts it)."""
    out: Matrix = (cov + cov.T) / 2.0
    return out
