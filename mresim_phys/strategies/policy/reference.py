"""Reference policies (phase 4, decide): plain callables a ``policy`` robot can be given,
for examples and tests (``policy: mresim_phys.strategies.policy.reference:nearest_frontier``).
"""

from __future__ import annotations

import numpy as np


def nearest_frontier(observation: dict[str, np.ndarray]) -> int:
    """The nearest valid frontier slot (slot 1 is the nearest by path); with none, the
    base (the last slot); with that not valid either, continue."""
    mask = observation["action_mask"].astype(bool)
    frontier_slots = np.flatnonzero(mask[1:-1]) + 1
    if len(frontier_slots):
        return int(frontier_slots[0])
    return len(mask) - 1 if mask[-1] else 0


def least_cost(observation: dict[str, np.ndarray]) -> int:
    """The valid slot of least path cost (``continue`` without a target costs the most);
    ties: the first slot."""
    scores = np.where(
        observation["action_mask"].astype(bool), -observation["candidates"][:, 2], -np.inf
    )
    return int(np.argmax(scores))
