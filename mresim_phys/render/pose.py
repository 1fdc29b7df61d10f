"""Views (phase 8), believed poses: where a robot with localisation thinks it is.

A robot with a ``localization:`` block is drawn at its true pose (``render.draw``); its
snapshot's :class:`~mresim_phys.localization.feature.PoseBelief` says where it believes
it is. Where its ``localization`` layer is on, :func:`draw_beliefs` adds, under the
robots' glyphs: a thin line from the true to the believed position, the 95 % ellipse of
the believed position's covariance (semi-axes ``sqrt(5.991 * eigenvalue)``, the
chi-square quantile of two degrees of freedom; none while the ellipse is under half a
pixel) and a hollow circle in the robot's colour at the believed position. A robot's path
and goal are plans in its believed frame, so its drawn path starts at the believed
position (:func:`path_start`). Robots without localisation draw nothing here, so their
frames are what they were before.

Typical use: ``draw_beliefs(image, snap.robots, centres, colours, layers, overlay.px,
overlay.to_px, sizes)``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

import cv2
import numpy as np

from mresim_phys.localization.feature import LOCALIZATION, PoseBelief
from mresim_phys.render.style import AA, BGR, ONE, SHIFT

if TYPE_CHECKING:
    from mresim_phys.snapshot import AgentSnapshot

LAYER = "localization"  # the robot layer that shows believed poses
CHI2_95 = 5.991  # chi-square quantile, 2 degrees of freedom, 95 %
MARKER_WIDTH = 2  # pixels: the believed position's hollow circle
ToPixels = Callable[[Sequence[float] | np.ndarray], np.ndarray]  # world -> fixed-point pixels


def belief_of(robot: AgentSnapshot) -> PoseBelief | None:
    """The robot's believed pose (None: it has no localisation)."""
    return LOCALIZATION.of(robot)


def path_start(robot: AgentSnapshot) -> tuple[float, float]:
    """Where a robot's drawn path starts: its believed position with localisation (its
    plans are in its believed frame), else its position."""
    belief = belief_of(robot)
    return robot.position if belief is None else (belief.pose[0], belief.pose[1])


def shows_beliefs(robots: Sequence[AgentSnapshot], layers: Sequence[frozenset[str]]) -> bool:
    """Whether some robot with localisation has its ``localization`` layer on (the
    legend's believed pose entry); ``layers`` are the robots' own, in order."""
    return any(
        LAYER in mine and belief_of(robot) is not None
        for robot, mine in zip(robots, layers, strict=True)
    )


def draw_beliefs(
    image: np.ndarray,
    robots: Sequence[AgentSnapshot],
    centres: np.ndarray,
    colours: Sequence[BGR],
    layers: Sequence[frozenset[str]],
    px: ToPixels,
    to_px: np.ndarray,
    sizes: Sequence[float],
) -> None:
    """Every shown believed pose (module docstring). ``centres`` are the robots' true
    positions, ``colours``, ``layers`` and ``sizes`` (glyph radii, pixels) theirs, in
    order; ``px`` converts world points to fixed-point pixels, ``to_px`` (2,) is its
    fixed-point units per cell along x and y."""
    for robot, centre, colour, mine, size in zip(
        robots, centres, colours, layers, sizes, strict=True
    ):
        belief = belief_of(robot)
        if belief is not None and LAYER in mine:
            draw_belief(image, belief, centre, colour, px, to_px, size)


def draw_belief(
    image: np.ndarray,
    belief: PoseBelief,
    centre: np.ndarray,
    colour: BGR,
    px: ToPixels,
    to_px: np.ndarray,
    size: float,
) -> None:
    """One robot's line from its true position ``centre`` (fixed point) to its believed
    one, its 95 % ellipse and the hollow circle at the believed position."""
    at = px(belief.pose[:2])
    true = (int(centre[0]), int(centre[1]))
    spot = (int(at[0]), int(at[1]))
    cv2.line(image, true, spot, colour, 1, AA, SHIFT)
    ellipse = ellipse_axes(belief, to_px)
    if ellipse is not None:
        axes, angle = ellipse
        cv2.ellipse(image, spot, axes, angle, 0.0, 360.0, colour, 1, AA, SHIFT)
    cv2.circle(image, spot, round(size * ONE), colour, MARKER_WIDTH, AA, SHIFT)


def ellipse_axes(belief: PoseBelief, to_px: np.ndarray) -> tuple[tuple[int, int], float] | None:
    """The 95 % ellipse of the believed position in fixed-point pixels: (semi-major,
    semi-minor) and the major axis' angle in degrees (pixels' x right, y down, as cv2
    turns it); None when the ellipse is under half a pixel (a covariance of about 0)."""
    scale = np.diag(np.asarray(to_px, dtype=float))
    cov = scale @ belief.covariance()[:2, :2] @ scale  # fixed-point units squared
    values, vectors = np.linalg.eigh(cov)  # ascending
    major, minor = (math.sqrt(CHI2_95 * max(float(v), 0.0)) for v in values[::-1])
    if major < ONE / 2:
        return None
    angle = math.degrees(math.atan2(float(vectors[1, 1]), float(vectors[0, 1])))
    return (round(major), round(minor)), angle
