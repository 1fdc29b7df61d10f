"""Rewards (learning interface): each policy robot's reward for one step, from documented,
weighted components (``config.RewardWeights``, docs/learning.md):

    r = explored_own * (cells newly known in its own map)
      + explored_team * (cells the team newly explored)
      + known_at_base * (cells newly known at the base station)
      - time (every step it is in the episode)
      - failure (once, on the step it fails)

The team's and the base's cells are the step's gain in the ``explored`` and
``known_at_base`` fractions times the team's explorable cells (docs/explorable.md).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mresim_phys.learn.config import RewardWeights
from mresim_phys.metrics import StepRecord
from mresim_phys.types import UNKNOWN


@dataclass
class RewardState:
    """What the last reward was measured against."""

    explored: float
    at_base: float
    known: dict[str, int]


def known_cells(belief: np.ndarray) -> int:
    """Cells a map knows (free or obstacle)."""
    return int(belief.size - np.count_nonzero(belief == UNKNOWN))


def team_gains(state: RewardState, record: StepRecord, area: int) -> tuple[float, float]:
    """(cells the team newly explored, cells newly known at the base) since ``state``;
    ``state`` moves on to ``record``."""
    team = (record.explored - state.explored) * area
    base = (record.known_at_base - state.at_base) * area
    state.explored, state.at_base = record.explored, record.known_at_base
    return team, base


def reward(weights: RewardWeights, own: int, team: float, base: float, failed: bool) -> float:
    """One robot's reward for a step (module docstring)."""
    value = weights.explored_own * own + weights.explored_team * team
    value += weights.known_at_base * base - weights.time
    return float(value - (weights.failure if failed else 0.0))
