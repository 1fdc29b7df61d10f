"""Localisation, a per-robot feature (phase 5, move and sense): a believed pose beside the true.

A robot with a scenario ``localization:`` block has the state :class:`Localization` in
``Robot.features["localization"]``. ``Robot.position`` and ``Robot.heading`` stay the
**true** pose: physics, the laser's rays, radio geometry, hazards, frames. The state holds
the **believed** pose and its covariance (:class:`~mresim_phys.localization.estimate.PoseEstimate`):
what the robot's map, its planning, its teammate record and its strategy's view use
(``Robot.believed``). This module alone moves both poses together:

* :meth:`Localization.drive`: a leg commanded in the believed frame (from the believed
  pose to a point of the path) becomes an odometry :class:`~.odometry.Motion`; the body
  executes it with noise from the robot's ``odometry`` stream (its true end is checked
  against the walls by ``motion.py``), the believed pose moves by it exactly and its
  covariance grows by the EKF prediction; :meth:`Localization.turn` is a turn in place;
* :meth:`Localization.to_believed`: a point seen from the true pose, placed where the
  robot believes it (a contact, a scan's end points: ``sensing_phase.py``);
* :meth:`Localization.fix`: a Kalman update from a correction (``corrections.py``).

The feature's value (:class:`PoseBelief`: the believed pose, its covariance and the
error against the truth) is what a strategy sees, a snapshot records, the run log stores
under ``localization`` (a list of 11 floats), frames draw (the ``localization`` layer) and
the viewer's hover row shows; the metric columns ``pose_error`` (per robot),
``heading_error`` (per robot, degrees), ``pose_error_mean`` and ``pose_error_max`` read it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from mresim_phys.columns import column
from mresim_phys.features import RobotFeature
from mresim_phys.localization.estimate import PoseEstimate
from mresim_phys.localization.odometry import (
    Motion,
    OdometryNoise,
    Pose,
    executed,
    motion_between,
    moved,
    wrap,
)
from mresim_phys.localization.scan_match import LiveField
from mresim_phys.localization.spec import LocalizationSpec, ScanMatchFix

if TYPE_CHECKING:
    from mresim_phys.metrics import StepRecord


@dataclass
class Localization:
    """A robot's believed pose beside its true one (module docstring)."""

    spec: LocalizationSpec
    noise: OdometryNoise
    odometry: np.random.Generator  # the body's motion noise
    fixes: np.random.Generator  # the corrections' measurement noise
    jumps: np.random.Generator  # the direction of a localisation fault's jump
    estimate: PoseEstimate
    true: Pose  # kept equal to (Robot.position, Robot.heading) by this module's callers
    bounds: tuple[float, float]  # the map's width and height: a belief stays on the map
    scans: int = 0  # scans taken (scan matching: every k-th)
    corrected: dict[str, int] = field(default_factory=dict)  # corrections fused, per kind
    live: LiveField | None = None  # scan matching: its map's likelihood field

    @property
    def matching(self) -> ScanMatchFix | None:
        """Its scan matching correction, if it has one."""
        return self.spec.matching

    @property
    def believed(self) -> Pose:
        """The believed pose (the estimate's mean)."""
        return self.estimate.mean

    def leg(self, end: tuple[float, float]) -> tuple[Motion, Pose]:
        """The motion from the believed pose to ``end`` (believed frame), turning to face
        it (a leg of no length keeps the heading), and the believed pose it ends at."""
        x, y, theta = self.believed
        heading = math.atan2(end[1] - y, end[0] - x) if (end[0], end[1]) != (x, y) else theta
        target = (end[0], end[1], heading)
        return motion_between(self.believed, target), target

    def drive(self, motion: Motion, target: Pose) -> Pose:
        """The true pose after the body executes ``motion`` towards the believed ``target``
        (three draws from the odometry stream, always); nothing moves yet (:meth:`arrive`)."""
        done = executed(motion, self.noise, self.odometry)
        if done == motion and self.true == self.believed:
            return target  # no drift: exactly where the odometry says
        return moved(self.true, done)

    def arrive(self, motion: Motion, target: Pose, true: Pose, frozen: bool = False) -> None:
        """``motion`` was made and the body is at ``true``: the believed pose is the
        odometry's ``target``, its covariance grows by the EKF prediction (``frozen``: a
        localisation fault holds the belief where it was)."""
        self.true = true
        if frozen:
            return
        cov = self.estimate.predicted(motion, self.noise).cov
        self.estimate = self._on_map(PoseEstimate(target, cov))

    def turn(self, heading: float, frozen: bool = False) -> float:
        """Turn in place to believed ``heading``; the true heading after it."""
        x, y, theta = self.believed
        motion, target = Motion(0.0, 0.0, wrap(heading - theta)), (x, y, heading)
        true = self.drive(motion, target)
        self.arrive(motion, target, true, frozen)
        return true[2]

    def jump(self, distance: float) -> None:
        """A localisation fault throws the believed pose ``distance`` cells off, in a
        direction drawn from the jump stream; the robot does not know (its covariance
        stays): the kidnapped robot."""
        angle = float(self.jumps.uniform(-math.pi, math.pi))
        x, y, theta = self.believed
        moved_to = (x + distance * math.cos(angle), y + distance * math.sin(angle), theta)
        self.estimate = self._on_map(PoseEstimate(moved_to, self.estimate.cov))

    def to_believed(self, point: tuple[float, float]) -> tuple[float, float]:
        """``point`` (true frame) as the robot places it: seen from its true pose, drawn
        from its believed pose."""
        tx, ty, tt = self.true
        bx, by, bt = self.believed
        turn = bt - tt
        dx, dy = point[0] - tx, point[1] - ty
        c, s = math.cos(turn), math.sin(turn)
        return (bx + c * dx - s * dy, by + s * dx + c * dy)

    def fix(self, estimate: PoseEstimate, note: str) -> None:
        """Take a corrected estimate (kept on the map); ``note`` says which correction."""
        self.estimate = self._on_map(estimate)
        self.corrected[note] = self.corrected.get(note, 0) + 1

    def _on_map(self, estimate: PoseEstimate) -> PoseEstimate:
        """``estimate`` with its mean inside the map (a robot knows its map's extent)."""
        x, y, theta = estimate.mean
        width, height = self.bounds
        inside = (min(max(x, 0.5), width - 0.5), min(max(y, 0.5), height - 0.5))
        if inside == (x, y):
            return estimate
        return PoseEstimate((*inside, theta), estimate.cov)

    def error(self) -> tuple[float, float]:
        """(position error in cells, heading error in rad) of the belief against the truth."""
        (tx, ty, tt), (bx, by, bt) = self.true, self.believed
        return math.hypot(bx - tx, by - ty), abs(wrap(bt - tt))


Streams3 = tuple[np.random.Generator, np.random.Generator, np.random.Generator]


def localize(
    spec: LocalizationSpec, pose: Pose, streams: Streams3, bounds: tuple[float, float]
) -> Localization:
    """A robot's localisation state at its start (its pose known exactly); ``streams``:
    its odometry, pose-fix and jump streams."""
    noise = OdometryNoise(*spec.odometry.alpha)
    odometry, fixes, jumps = streams
    estimate = PoseEstimate.certain(pose)
    return Localization(spec, noise, odometry, fixes, jumps, estimate, pose, bounds)


FIX_NOTES = ("base", "beacon", "teammate", "scan_matching")  # the corrections, as counted


@dataclass(frozen=True)
class PoseBelief:
    """What a robot believes of its pose: the believed pose, the covariance's six distinct
    entries (xx, xy, yy, xt, yt, tt), its error against the truth (cells, rad) and the
    corrections it fused so far, per kind of :data:`FIX_NOTES`."""

    pose: Pose
    cov: tuple[float, float, float, float, float, float]
    error: float
    heading_error: float
    fixes: tuple[int, int, int, int] = (0, 0, 0, 0)

    def corrections(self) -> dict[str, int]:
        """The corrections fused so far, by kind (those fused at least once)."""
        return {note: n for note, n in sorted(zip(FIX_NOTES, self.fixes, strict=True)) if n}

    @property
    def sigma(self) -> float:
        """The position's standard deviation along its worst axis (cells)."""
        xx, xy, yy = self.cov[0], self.cov[1], self.cov[2]
        half = (xx + yy) / 2.0
        return math.sqrt(max(half + math.hypot((xx - yy) / 2.0, xy), 0.0))

    def covariance(self) -> np.ndarray:
        """The 3x3 covariance."""
        xx, xy, yy, xt, yt, tt = self.cov
        return np.array([[xx, xy, xt], [xy, yy, yt], [xt, yt, tt]])


class LocalizationFeature(RobotFeature[Localization, PoseBelief]):
    """The believed pose, its covariance and its error (module docstring)."""

    key = "localization"
    layer = "localization"

    def value(self, state: Localization) -> PoseBelief:
        """The belief and its error."""
        c = state.estimate.cov
        cov = (c[0, 0], c[0, 1], c[1, 1], c[0, 2], c[1, 2], c[2, 2])
        error, heading = state.error()
        fixes = tuple(state.corrected.get(note, 0) for note in FIX_NOTES)
        return PoseBelief(state.believed, tuple(float(v) for v in cov), error, heading, fixes)  # type: ignore[arg-type]

    def encode(self, value: PoseBelief) -> Any:
        """[x, y, theta, six covariance entries, error, heading error, the four counts of
        corrections], full precision."""
        return [*value.pose, *value.cov, value.error, value.heading_error, *value.fixes]

    def decode(self, raw: Any) -> PoseBelief:
        """The logged list (a log before the counts of corrections: none counted)."""
        v = [float(x) for x in raw[:11]]
        n = tuple(int(x) for x in raw[11:15]) if len(raw) >= 15 else (0, 0, 0, 0)
        cov = (v[3], v[4], v[5], v[6], v[7], v[8])
        return PoseBelief((v[0], v[1], v[2]), cov, v[9], v[10], n)  # type: ignore[arg-type]

    def label(self, value: PoseBelief) -> str:
        """`` ~1.4`` (the position error, cells)."""
        return f" ~{value.error:.1f}"

    def hover(self, value: PoseBelief) -> Any:
        """The believed pose, the error and the position sigma."""
        return {
            "believed": [round(value.pose[0], 2), round(value.pose[1], 2)],
            "heading_deg": round(math.degrees(value.pose[2]), 1),
            "error": round(value.error, 3),
            "sigma": round(value.sigma, 3),
        }


LOCALIZATION = LocalizationFeature()


def believed_pose(states: Mapping[str, Any], position: tuple[float, float], heading: float) -> Pose:
    """The pose a robot with feature ``states`` believes it has (its true pose without
    the feature)."""
    state: Localization | None = states.get(LOCALIZATION.key)
    return (*position, heading) if state is None else state.believed


def _errors(r: StepRecord) -> list[float | None]:
    """Each robot's position error (None without localisation)."""
    beliefs = (LOCALIZATION.of(robot) for robot in r.robots)
    return [None if b is None else b.error for b in beliefs]


@column("pose_error", per_robot=True, optional=True)
def pose_error(r: StepRecord) -> Sequence[float | None]:
    """Each robot's position error: believed to true position, cells ('' without
    localisation)."""
    return _errors(r)


@column("heading_error", per_robot=True, optional=True)
def heading_error(r: StepRecord) -> Sequence[float | None]:
    """Each robot's heading error, degrees ('' without localisation)."""
    beliefs = (LOCALIZATION.of(robot) for robot in r.robots)
    return [None if b is None else math.degrees(b.heading_error) for b in beliefs]


@column("pose_error_mean", optional=True)
def pose_error_mean(r: StepRecord) -> float | None:
    """The mean position error of the robots with localisation that are not failed."""
    errors = _alive_errors(r)
    return float(np.mean(errors)) if errors else None


@column("pose_error_max", optional=True)
def pose_error_max(r: StepRecord) -> float | None:
    """The largest position error of the robots with localisation that are not failed."""
    errors = _alive_errors(r)
    return max(errors) if errors else None


def _alive_errors(r: StepRecord) -> list[float]:
    """The position errors of the robots with localisation that are not failed."""
    alive = [robot.state != "failed" for robot in r.robots]
    return [e for e, a in zip(_errors(r), alive, strict=True) if e is not None and a]
