"""Sensing (phase 2): a laser's readings through the beam model, from the exact cast.

A real laser does not return the distance to the first wall. The beam model (Thrun,
Burgard and Fox, *Probabilistic Robotics*, 6.3; the ``laser_model_type: beam`` of ROS
AMCL, whose names these are) reads each ray as one of four kinds, drawn with the weights
``z_hit + z_short + z_max + z_rand = 1``:

* **hit**: the true distance ``z*`` plus Gaussian noise of ``sigma_hit`` cells (a ray with
  nothing within range has no return);
* **short**: something unmapped in the way, at an exponential distance of rate
  ``lambda_short`` truncated to ``[0, z*)``;
* **max**: no return at all (a dark or glassy surface, a missed echo);
* **rand**: a uniform reading on ``[0, max range)``;

and, apart from the mixture, each ray is lost with probability ``dropout`` (no reading).
The robot may filter the readings before it maps them: with ``speckle`` (cells), a return
farther than that from every other return within ``speckle_window`` rays on either side is
left out (a speckle filter, as ROS laser_filters has: an isolated return is most often a
short or random one).

What the robot can tell: a reading below the maximum range is a return, and its end an
obstacle (a *short* or *rand* return is a phantom one, with no wall face to join); the map
weighs every reading as evidence (``knowledge/evidence.py``), so one stray return makes no
wall. A reading at the maximum range has no return: it marks **no obstacle**, and the
cells along it free only up to ``max_free`` cells (default: the whole range, the exact
laser's rule). Set it lower when no-returns are frequent: a no-return ray that should
have hit a wall near by would free the cells behind that wall; ``max_free: 0`` leaves such
rays out of the map (as a lost ray). A ray left out keeps its place in the scan with
length 0, so the free area ends at the robot along it: what lies between its neighbours is
not taken as free (a small obstacle there could be swallowed) until another scan sees it.
A ray that ends on a robot (when robots block rays) keeps its reading and marks no
obstacle, as without the model.

Every ray takes :data:`DRAWS` uniform draws from the robot's ``sensing`` stream, whatever
it reads, so the draws of one scan never shift those of the next. :func:`read_rays` is
compiled: the queued scans of a turn read and fold in one call (``knowledge/beamfold.py``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from numba import njit

from mresim_phys.types import FloatArray
from mresim_phys.world.space import Scan

DRAWS = 5  # uniform draws per ray: kind, reading, dropout and two for a Gaussian
KINDS = ("hit", "short", "max", "rand", "dropped", "filtered")  # the counts' order


@dataclass(frozen=True)
class Beam:
    """The beam model's weights and shapes (module docstring); lengths in cells."""

    z_hit: float = 1.0
    z_short: float = 0.0
    z_max: float = 0.0
    z_rand: float = 0.0
    sigma_hit: float = 0.0
    lambda_short: float = 0.1
    dropout: float = 0.0
    max_free: float | None = None  # None: the laser's range
    speckle: float | None = None  # the robot's speckle filter (cells); None: off
    speckle_window: int = 2  # rays each side a return is compared with

    def params(self, max_range: float) -> FloatArray:
        """The model as the kernel reads it: the cumulative weights, sigma, lambda, the
        dropout, the free length of a no-return ray (at most ``max_range``), the speckle
        filter's distance (0: off) and window."""
        free = max_range if self.max_free is None else min(self.max_free, max_range)
        cumulative = np.cumsum([self.z_hit, self.z_short, self.z_max, self.z_rand])
        speckle = 0.0 if self.speckle is None else self.speckle
        return np.array(
            [*cumulative[:3], self.sigma_hit, self.lambda_short, self.dropout, free, speckle,
             self.speckle_window],
            dtype=np.float64,
        )  # fmt: skip


@njit(cache=True, nogil=True)
def read_rays(
    ranges: FloatArray,
    normals: FloatArray,
    wall_hit: np.ndarray,
    max_range: float,
    params: FloatArray,
    draws: FloatArray,
    counts: np.ndarray,
) -> None:
    """Turn the exact cast (``ranges``, ``normals``, ``wall_hit``, rewritten in place) into
    the readings of the model ``params`` (:meth:`Beam.params`), ray ``k`` from
    ``draws[k]``; add each ray's kind to ``counts`` (:data:`KINDS`). A ray left out of the
    map (lost, filtered, or no return with ``max_free`` 0) gets length 0 and no return."""
    n = len(ranges)
    to_hit, to_short, to_max = params[0], params[1], params[2]
    sigma, rate, dropout, free = params[3], params[4], params[5], params[6]
    for k in range(n):
        u = draws[k]
        true = ranges[k]
        if u[2] < dropout:
            _leave_out(ranges, normals, wall_hit, k)
            counts[4] += 1
            continue
        if u[0] < to_hit:
            kind = 0
            reading = max_range
            if true < max_range:
                gauss = math.sqrt(-2.0 * math.log(1.0 - u[3])) * math.cos(2.0 * math.pi * u[4])
                reading = min(max(true + sigma * gauss, 0.0), max_range)
        elif u[0] < to_short:
            kind = 1
            reading = -math.log(1.0 - u[1] * (1.0 - math.exp(-rate * true))) / rate
            reading = min(reading, true)
        elif u[0] < to_max:
            kind = 2
            reading = max_range
        else:
            kind = 3
            reading = u[1] * max_range
        counts[kind] += 1
        if reading >= max_range:  # no return: no obstacle, free up to ``free``
            _leave_out(ranges, normals, wall_hit, k)
            ranges[k] = free
            continue
        if kind != 0:  # a phantom return: an obstacle with no face to join
            normals[k, 0], normals[k, 1], wall_hit[k] = 0.0, 0.0, True
        ranges[k] = reading
    if params[7] > 0.0:
        speckle_filter(ranges, wall_hit, normals, max_range, params[7], int(params[8]), counts)


@njit(cache=True, nogil=True, inline="always")
def _leave_out(ranges: FloatArray, normals: FloatArray, wall_hit: np.ndarray, k: int) -> None:
    """Ray ``k`` tells the map nothing: no length, no return."""
    ranges[k], normals[k, 0], normals[k, 1], wall_hit[k] = 0.0, 0.0, 0.0, False


@njit(cache=True, nogil=True)
def speckle_filter(
    ranges: FloatArray,
    wall_hit: np.ndarray,
    normals: FloatArray,
    max_range: float,
    distance: float,
    window: int,
    counts: np.ndarray,
) -> None:
    """Leave out of the map every return (a reading of length above 0 below
    ``max_range``) farther than ``distance`` from every other return within ``window``
    rays on either side: an isolated reading, most likely a short or random one (ROS
    laser_filters' ``LaserScanSpeckleFilter``, its distance rule); counted as filtered."""
    n = len(ranges)
    returned = (ranges > 0.0) & (ranges < max_range)
    for k in range(n):
        if not returned[k]:
            continue
        near = False
        for j in range(max(k - window, 0), min(k + window + 1, n)):
            if j != k and returned[j] and abs(ranges[j] - ranges[k]) <= distance:
                near = True
                break
        if not near:
            _leave_out(ranges, normals, wall_hit, k)
            counts[5] += 1


def read_beam(scan: Scan, beam: Beam, rng: np.random.Generator, counts: np.ndarray) -> Scan:
    """``scan`` (an exact cast) as the beam model reads it; the readings' kinds added to
    ``counts``."""
    ranges, normals = scan.ranges.copy(), scan.normals.copy()
    wall_hit = scan.wall_hit.copy()
    draws = rng.random((len(ranges), DRAWS))
    params = beam.params(scan.max_range)
    read_rays(ranges, normals, wall_hit, float(scan.max_range), params, draws, counts)
    return replace(scan, ranges=ranges, normals=normals, wall_hit=wall_hit)
