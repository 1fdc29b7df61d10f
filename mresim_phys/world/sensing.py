"""Sensing (phase 2): a robot's laser scan at its pose, cast in the true world.

A scan is ``rays`` rays spread evenly over ``fov_deg`` centred on the heading
(181 rays over 180 degrees = 1 degree apart, as the original), each ending at the
exact distance to the first wall (``world/raycast.py``: one compiled call per scan) or at
the maximum range. Noise-free unless the sensor has ``noise_std`` or a beam model
(``world/beam.py``, read by the sensing phase); noise comes from the robot's own
``sensing`` stream so it never shifts any other random draw.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np

from mresim_phys.types import FloatArray
from mresim_phys.world.beam import Beam
from mresim_phys.world.space import Scan, World


@dataclass(frozen=True)
class Laser:
    """A planar laser scanner: ``rays`` rays evenly over ``fov_deg`` centred on the heading."""

    range: float  # cells
    fov_deg: float = 180.0
    rays: int = 181
    noise_std: float = 0.0  # Gaussian range noise (cells) on rays that hit something
    safe_fraction: float = 0.1  # safe space: rays clipped to this fraction of the range
    beam: Beam | None = None  # the beam model's readings (``world/beam.py``); None: exact

    @property
    def exact(self) -> bool:
        """Whether its readings are the exact distances (no noise, no beam model)."""
        return self.noise_std <= 0 and self.beam is None


@lru_cache(maxsize=64)
def ray_offsets(fov_deg: float, rays: int) -> FloatArray:
    """Ray angles relative to the heading, radians, evenly spread over the field of view.

    >>> np.round(np.degrees(ray_offsets(180.0, 5)), 6).tolist()
    [-90.0, -45.0, 0.0, 45.0, 90.0]
    """
    half = np.radians(fov_deg) / 2.0
    if fov_deg >= 360.0:
        return np.linspace(-np.pi, np.pi, rays, endpoint=False)
    return np.linspace(-half, half, rays)


def scan(
    world: World,
    origin: tuple[float, float],
    heading: float,
    sensor: Laser,
    shape_filter: tuple[int, int, int],
    rng: np.random.Generator | None = None,
) -> Scan:
    """One scan from ``origin`` facing ``heading`` (radians, 0 = +x, y grows down)."""
    angles = heading + ray_offsets(sensor.fov_deg, sensor.rays)
    result = world.cast_rays(origin, angles, sensor.range, shape_filter)
    if sensor.noise_std > 0 and rng is not None:
        result = add_range_noise(result, sensor.noise_std, rng)
    return result


def add_range_noise(result: Scan, std: float, rng: np.random.Generator) -> Scan:
    """Gaussian noise on the ranges of rays that hit something, clipped to [0, max range]."""
    noisy = result.ranges + rng.normal(0.0, std, size=result.ranges.shape) * (
        result.ranges < result.max_range
    )
    return replace(result, ranges=np.clip(noisy, 0.0, result.max_range))
