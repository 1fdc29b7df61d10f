"""Burst losses (phase 6, links): a Gilbert-Elliott two-state channel per agent pair.

Every pair of agents has a state, good or bad, that moves as a Markov chain each step
(good to bad with ``good_to_bad``, bad to good with ``bad_to_good``); in each state a
linked pair loses its link for the step with that state's loss probability. The first
state is drawn from the chain's stationary distribution (bad with probability
``good_to_bad / (good_to_bad + bad_to_good)``), so the long-run loss rate
``pi_bad * loss_bad + (1 - pi_bad) * loss_good`` holds from the first step. Every draw
comes from the channel's ``bursts-<channel>`` stream, for every pair every step whether
or not it is in range: the same seed gives the same bursts whatever the robots do.
"""

from __future__ import annotations

import numpy as np

from mresim_phys.comms.radio_params import BurstSpec


class GilbertElliott:
    """The burst state of every pair of ``n`` agents (upper triangle, row-major)."""

    def __init__(self, spec: BurstSpec, n: int, rng: np.random.Generator) -> None:
        self.spec, self.rng = spec, rng
        self.rows, self.cols = np.triu_indices(n, k=1)
        self.bad = rng.random(len(self.rows)) < spec.stationary_bad

    def step(self) -> np.ndarray:
        """Advance every pair's chain one step; return which pairs lose their link now."""
        s = self.spec
        move = self.rng.random(len(self.rows))
        self.bad = np.where(self.bad, move >= s.bad_to_good, move < s.good_to_bad)
        loss = np.where(self.bad, s.loss_bad, s.loss_good)
        lost: np.ndarray = self.rng.random(len(self.rows)) < loss
        return lost

    def lost(self, n: int) -> np.ndarray:
        """This step's lost links as a symmetric (n, n) matrix (advances the chains)."""
        draw = self.step()
        matrix = np.zeros((n, n), dtype=bool)
        matrix[self.rows[draw], self.cols[draw]] = True
        matrix[self.cols[draw], self.rows[draw]] = True
        return matrix
