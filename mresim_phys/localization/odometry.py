"""Odometry motion model (phase 5, move): how far a robot's true pose drifts from its odometry.

A robot drives a motion in its believed frame: a turn towards the next point, a straight
leg, a turn at its end. Its wheels report that motion exactly (the *odometry*: the
believed pose moves by it), while the body executes it with noise. The model is the
odometry motion model of Thrun, Burgard and Fox (*Probabilistic Robotics*, 2005, table
5.6). A motion from pose (x, y, theta) is decomposed as

    rot1  = atan2(y' - y, x' - x) - theta
    trans = hypot(x' - x, y' - y)
    rot2  = theta' - theta - rot1

and executed as

    rot1^  = rot1  - e1,  e1 ~ N(0, a1 rot1^2 + a2 trans^2)
    trans^ = trans - e2,  e2 ~ N(0, a3 trans^2 + a4 (rot1^2 + rot2^2))
    rot2^  = rot2  - e3,  e3 ~ N(0, a1 rot2^2 + a2 trans^2)

    x' = x + trans^ cos(theta + rot1^),  y' = y + trans^ sin(theta + rot1^),
    theta' = theta + rot1^ + rot2^

with ``alpha = (a1, a2, a3, a4)``: a1 the rotation noise per rotation (rad^2 / rad^2), a2
per translation (rad^2 / cell^2), a3 the translation noise per translation (cell^2 /
cell^2), a4 per rotation (cell^2 / rad^2). Zero alphas execute the motion exactly (every
draw is 0.0), so a run with them is the noise-free run. The draws come from the robot's
own named stream, so the same drift strikes a robot whatever its strategy does with it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

Pose = tuple[float, float, float]  # x, y (cells), heading (rad)


@dataclass(frozen=True)
class Motion:
    """One motion in the odometry model's terms: turn, straight leg, turn."""

    rot1: float
    trans: float
    rot2: float


@dataclass(frozen=True)
class OdometryNoise:
    """The model's four noise parameters (module docstring); all >= 0."""

    a1: float
    a2: float
    a3: float
    a4: float

    def __post_init__(self) -> None:
        for name in ("a1", "a2", "a3", "a4"):
            value = getattr(self, name)
            if not math.isfinite(value) or value < 0:
                raise ValueError(f"odometry noise {name} must be a finite number >= 0: {value}")

    def variances(self, motion: Motion) -> tuple[float, float, float]:
        """The variances of the noise on rot1, trans and rot2 for ``motion``."""
        r1, t, r2 = motion.rot1**2, motion.trans**2, motion.rot2**2
        return (self.a1 * r1 + self.a2 * t, self.a3 * t + self.a4 * (r1 + r2),
                self.a1 * r2 + self.a2 * t)  # fmt: skip


def wrap(angle: float) -> float:
    """``angle`` in [-pi, pi).

    >>> round(wrap(3 * math.pi / 2), 6) == round(-math.pi / 2, 6)
    True
    """
    return (angle + math.pi) % (2 * math.pi) - math.pi


def motion_between(start: Pose, end: Pose) -> Motion:
    """The motion that takes a robot from pose ``start`` to pose ``end`` (a motion without
    translation is all ``rot2``: no heading to turn towards)."""
    dx, dy = end[0] - start[0], end[1] - start[1]
    trans = math.hypot(dx, dy)
    rot1 = wrap(math.atan2(dy, dx) - start[2]) if trans > 0 else 0.0
    return Motion(rot1, trans, wrap(end[2] - start[2] - rot1))


def moved(pose: Pose, motion: Motion) -> Pose:
    """``pose`` after ``motion`` executed exactly."""
    x, y, theta = pose
    heading = theta + motion.rot1
    return (x + motion.trans * math.cos(heading), y + motion.trans * math.sin(heading),
            wrap(heading + motion.rot2))  # fmt: skip


def executed(motion: Motion, noise: OdometryNoise, rng: np.random.Generator) -> Motion:
    """``motion`` as the body executes it: each part less a draw of its noise (three
    normal draws from ``rng``, always three, so the stream's use never depends on the
    motion)."""
    scales = np.sqrt(noise.variances(motion))
    e1, e2, e3 = (float(v) for v in rng.normal(0.0, 1.0, 3) * scales)
    return Motion(motion.rot1 - e1, motion.trans - e2, motion.rot2 - e3)
