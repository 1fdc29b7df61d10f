"""The frontier utility (phase 4, decide): what a frontier is worth to a robot at a cost.

The original's ``U = size * 1e8 / d**4`` (:func:`utility`), compiled so that it is the same
float on every processor, and :func:`pair_utilities`, the auction's rescoring of one
frontier's column of bidders (``strategies.auction``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from mresim_phys.types import FloatArray

UTILITY_SCALE = 1e8  # original: U = area * 10^8 / d^4


def utility(sizes: FloatArray, costs: FloatArray, power: int = 4) -> FloatArray:
    """The original's frontier utility ``size * 1e8 / d**4`` (``power``: another exponent
    of the distance, as a candidate order may use), ``sizes`` and ``costs`` broadcast
    together; unreachable frontiers get -inf.

    Compiled (:func:`_utility`, the C library's ``pow``) rather than numpy's ``**``: on a
    processor with AVX-512, numpy's power is a vector routine whose last bit differs from
    ``pow`` on some distances, so the same run chose other frontiers on other machines, and
    a bid rescored by :func:`pair_utilities` differed from its first score."""
    s, c = np.broadcast_arrays(np.asarray(sizes, np.float64), np.asarray(costs, np.float64))
    out = np.empty(c.shape)
    _utilities(s.ravel(), c.ravel(), float(power), out.reshape(-1))
    return out


@njit(cache=True, nogil=True)
def _utilities(sizes: FloatArray, costs: FloatArray, power: float, out: FloatArray) -> None:
    """:func:`_utility` of each (size, cost) pair into ``out``."""
    for i in range(len(costs)):
        out[i] = _utility(sizes[i], costs[i], power)


@njit(cache=True, nogil=True)
def pair_utilities(
    size: float, costs: FloatArray, high: FloatArray, u: FloatArray, u_low: FloatArray
) -> None:
    """:func:`utility` (power 4) of frontier ``size`` at each of ``costs`` into ``u`` and
    each of ``high`` into ``u_low``, without numpy's per-call cost (a refinement rescores a
    column of bidders a few hundred times a step on the campus)."""
    for i in range(len(costs)):
        u[i] = _utility(size, costs[i], 4.0)
        u_low[i] = _utility(size, high[i], 4.0)


@njit(cache=True, nogil=True, inline="always")
def _utility(size: float, cost: float, power: float) -> float:
    """One pair's :func:`utility`: -inf for an unreachable frontier."""
    if not np.isfinite(cost):
        return -np.inf
    value: float = size * UTILITY_SCALE / max(cost, 1.0) ** power
    return value
