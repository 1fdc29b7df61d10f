"""Pose corrections (phase 5 after the move, phase 6 after the exchange): measurements fused.

Each correction is a measurement drawn from the truth with the robot's ``pose-fix`` stream
and fused by the Kalman update of ``estimate.py`` (formulas in docs/localization.md):

* ``base``: within ``within`` cells of the base station (a known landmark), a fix of the
  robot's position, ``z = p + n``, ``n ~ N(0, sigma^2 I)``; after the robot's move;
* ``beacons``: the same fix from each beacon within ``range`` cells in line of sight
  (a ray from the true position reaches it), one beacon at a time, in the listed order;
* ``teammate``: after the communication phase, for each robot linked on the main
  channel: a range ``rho + n_r`` and bearing ``beta + n_b`` from the robot to the
  teammate (true poses), fused with the teammate's believed position and covariance
  as they were when the phase began (``PoseEstimate.ranged``), so the order of the
  robots never matters; a teammate without localisation is known exactly.

Two draws per position fix, three per teammate seen (range, bearing, and one kept for a
heading measurement to come); a robot out of every correction's reach draws nothing.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, Protocol

import numpy as np

from mresim_phys.localization.estimate import PoseEstimate
from mresim_phys.localization.faults import frozen
from mresim_phys.localization.feature import LOCALIZATION, Localization
from mresim_phys.localization.odometry import wrap
from mresim_phys.localization.spec import BaseFix, BeaconsFix, TeammateFix
from mresim_phys.world.queries import QueryFilter
from mresim_phys.world.space import World

Place = tuple[float, float]


class Teammate(Protocol):
    """What the teammate correction reads of a robot (``agents.Robot``)."""

    name: str
    position: Place  # the true position
    links: tuple[str, ...]  # the agents it is linked with on the main channel
    features: dict[str, Any]

    @property
    def alive(self) -> bool:
        """Whether it still senses, moves and communicates."""
        ...


def landmark_fixes(loc: Localization, base: Place, world: World, rays: QueryFilter) -> None:
    """The base and beacon fixes of a robot that has just moved (``rays``: what its line
    of sight to a beacon collides with)."""
    for fix in loc.spec.corrections:
        if isinstance(fix, BaseFix) and math.dist(loc.true[:2], base) <= fix.within:
            _position_fix(loc, fix.sigma, "base")
        elif isinstance(fix, BeaconsFix):
            for beacon in fix.positions:
                if _sees(world, loc.true[:2], beacon, fix.range, rays):
                    _position_fix(loc, fix.sigma, "beacon")


def _position_fix(loc: Localization, sigma: float, note: str) -> None:
    """A fix of the position with noise ``sigma``, fused."""
    x, y, _ = loc.true
    dx, dy = (float(v) for v in loc.fixes.normal(0.0, sigma, 2))
    loc.fix(loc.estimate.corrected((x + dx, y + dy), np.eye(2) * sigma**2), note)


def _sees(world: World, here: Place, there: Place, reach: float, rays: QueryFilter) -> bool:
    """Whether ``there`` is within ``reach`` of ``here`` and a ray reaches it."""
    gap = math.dist(here, there)
    if gap > reach:
        return False
    if gap <= 1e-9:
        return True
    angle = math.atan2(there[1] - here[1], there[0] - here[0])
    scan = world.cast_rays(here, np.array([angle]), gap, rays)
    return bool(scan.ranges[0] >= gap - 1e-6)


def teammate_fixes(robots: Sequence[Teammate]) -> None:
    """The teammate corrections after an exchange, for every robot that is not failed
    and has one, from the teammates it is linked with on the main channel."""
    team = [(r, LOCALIZATION.state_of(r.features)) for r in robots if r.alive]
    working = {r.name for r, _ in team if not frozen(r.features)}
    if not any(loc is not None and _teammate_fix(loc) for _, loc in team):
        return
    known = {r.name: (r.position, _estimate(r.position, loc)) for r, loc in team}  # as it began
    for robot, loc in team:
        fix = _teammate_fix(loc)
        if loc is None or fix is None or robot.name not in working:
            continue
        for other in robot.links:
            if other in known and other != robot.name:
                _ranged(loc, fix, robot.position, *known[other])


def _estimate(place: Place, loc: Localization | None) -> PoseEstimate:
    """A teammate's believed pose and covariance (exact without localisation)."""
    return PoseEstimate.certain((*place, 0.0)) if loc is None else loc.estimate


def _teammate_fix(loc: Localization | None) -> TeammateFix | None:
    """The robot's teammate correction, if it has one."""
    found = [c for c in loc.spec.corrections if isinstance(c, TeammateFix)] if loc else []
    return found[0] if found else None


def _ranged(
    loc: Localization, fix: TeammateFix, place: Place, their_place: Place,
    theirs: PoseEstimate,
) -> None:  # fmt: skip
    """One range and bearing to a teammate, fused."""
    dx, dy = their_place[0] - place[0], their_place[1] - place[1]
    if math.hypot(dx, dy) <= 1e-6:
        return  # on top of each other: no bearing
    sigma_bearing = math.radians(fix.sigma_bearing_deg)
    n = loc.fixes.normal(0.0, 1.0, 3)
    rho = math.hypot(dx, dy) + fix.sigma_range * float(n[0])
    beta = wrap(math.atan2(dy, dx) - loc.true[2] + sigma_bearing * float(n[1]))
    estimate = loc.estimate.ranged(theirs, (rho, beta), fix.sigma_range, sigma_bearing)
    loc.fix(estimate, "teammate")
