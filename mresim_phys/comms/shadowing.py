"""Shadowing and fast fading (phase 6, links): the random part of a radio's signal.

**Shadowing** is log-normal: a seeded Gaussian random field ``f`` over the map, unit
variance, with the Gaussian correlation ``rho(h) = exp(-(h / L)^2)`` at distance ``h``
(``L`` the correlation length). It is white noise (the channel's ``shadowing-<channel>``
stream, drawn once when the run is built) smoothed by a Gaussian kernel of standard
deviation ``L / 2`` (``scipy.ndimage.gaussian_filter``) and scaled by the kernel's norm, on
a grid padded beyond the kernel's reach so that the field is as stationary at the map's
edge as in its middle; beyond 8 cells of length, on nodes ``L // 8`` cells apart,
interpolated linearly. A link between agents at ``p_i`` and ``p_j`` (distance ``d``) gets

    X_ij = sigma * (f(p_i) + f(p_j)) / sqrt(2 * (1 + rho(d)))

dB added to its signal: symmetric, N(0, sigma^2) for every pair, and it changes only as
the agents move through the field, so links do not flicker independently every step.

**Fast fading** adds a fresh N(0, fading_db^2) per link and step from the channel's
``fading-<channel>`` stream, drawn for every pair every step whether or not it is in range
(the same seed fades the same links whatever the robots do).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import gaussian_filter

from mresim_phys.comms.radio_params import ShadowingSpec
from mresim_phys.types import FloatArray, IntArray

TRUNCATE = 4.0  # kernel standard deviations: where scipy's Gaussian kernel ends
NODES = 8  # field nodes per correlation length, at most: a longer length is drawn coarser


def correlation(h: FloatArray | float, length: float) -> FloatArray:
    """The field's correlation at distance ``h``: ``exp(-(h / length)^2)``."""
    return np.exp(-((np.asarray(h, dtype=float) / length) ** 2))


def shadow_field(shape: tuple[int, int], length: float, rng: np.random.Generator) -> FloatArray:
    """A unit-variance Gaussian field over a grid of ``shape`` with correlation
    :func:`correlation` (float32, one value per cell).

    A correlation length of :data:`NODES` cells or more is drawn on a coarser grid, one
    node every ``length // NODES`` cells, and interpolated linearly between nodes: the
    field barely changes between nodes that close (neighbours correlate at
    ``exp(-1/64)``), and the work and memory stay those of a map of a few hundred cells
    whatever the length (a length of the whole map, or beyond, is cheap)."""
    step = max(1, int(length // NODES))
    rows, cols = -(-shape[0] // step) + 1, -(-shape[1] // step) + 1
    sigma = length / 2.0 / step
    pad = int(np.ceil(TRUNCATE * sigma)) + 1
    noise = rng.standard_normal((rows + 2 * pad, cols + 2 * pad))
    smooth = gaussian_filter(noise, sigma, mode="constant", truncate=TRUNCATE)
    nodes = smooth[pad : pad + rows, pad : pad + cols] / kernel_norm(sigma)
    field = nodes[: shape[0], : shape[1]] if step == 1 else between(nodes, shape, step)
    return np.ascontiguousarray(field, dtype=np.float32)


def between(nodes: FloatArray, shape: tuple[int, int], step: int) -> FloatArray:
    """The field on every cell of ``shape`` from its ``nodes`` one every ``step`` cells,
    interpolated linearly along rows, then along columns."""
    for axis, size in enumerate(shape):
        at = np.arange(size) / step
        low = at.astype(np.int64)
        weight = (at - low).reshape((-1, 1) if axis == 0 else (1, -1))
        first = np.take(nodes, low, axis=axis)
        nodes = first + weight * (np.take(nodes, low + 1, axis=axis) - first)
    return nodes


def kernel_norm(sigma: float) -> float:
    """The L2 norm of scipy's discrete Gaussian kernel of ``sigma``: the standard deviation
    of white noise smoothed by it, away from any edge."""
    size = 2 * int(np.ceil(TRUNCATE * sigma)) + 1
    delta = np.zeros((size, size))
    delta[size // 2, size // 2] = 1.0
    kernel = gaussian_filter(delta, sigma, mode="constant", truncate=TRUNCATE)
    return float(np.sqrt(np.sum(kernel**2)))


@dataclass
class Shadowing:
    """One channel's shadowing field and its fast-fading stream."""

    spec: ShadowingSpec
    field: FloatArray
    fading_rng: np.random.Generator

    @classmethod
    def build(
        cls,
        spec: ShadowingSpec,
        shape: tuple[int, int],
        field_rng: np.random.Generator,
        fading_rng: np.random.Generator,
    ) -> Shadowing:
        """The field of ``spec`` over a map of ``shape`` from ``field_rng``."""
        return cls(spec, shadow_field(shape, spec.length, field_rng), fading_rng)

    def at(self, positions: FloatArray) -> FloatArray:
        """The unit field at each position (the cell under it, clipped to the map)."""
        rows = np.clip(positions[:, 1].astype(np.int64), 0, self.field.shape[0] - 1)
        cols = np.clip(positions[:, 0].astype(np.int64), 0, self.field.shape[1] - 1)
        return self.field[rows, cols].astype(np.float64)

    def pair_db(self, positions: FloatArray, rows: IntArray, cols: IntArray) -> FloatArray:
        """The shadowing (dB) of each link (rows[k], cols[k]): :math:`X_{ij}` above."""
        values = self.at(positions)
        gap = positions[rows] - positions[cols]
        rho = correlation(np.hypot(gap[:, 0], gap[:, 1]), self.spec.length)
        scale = self.spec.sigma_db / np.sqrt(2.0 * (1.0 + rho))
        return scale * (values[rows] + values[cols])

    def fading_db(self, pairs: int) -> FloatArray:
        """This step's fast fading (dB) of every one of ``pairs`` agent pairs."""
        if self.spec.fading_db <= 0:
            return np.zeros(pairs)
        return self.spec.fading_db * self.fading_rng.standard_normal(pairs)
