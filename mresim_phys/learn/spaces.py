"""Spaces (learning interface): the Gymnasium spaces of a policy robot's observation and
action, and of the privileged state (docs/learning.md has each array's meaning)."""

from __future__ import annotations

import numpy as np
from gymnasium import spaces

from mresim_phys.strategies.params import PolicyParams
from mresim_phys.strategies.policy.candidates import slot_count
from mresim_phys.strategies.policy.observe import OWN_SIZE, TEAMMATE_SIZE

STATE_ROBOT = 3  # per possible robot in the state: x, y (over the map's size), alive


def observation_space(params: PolicyParams) -> spaces.Dict:
    """The ``Dict`` space of ``observe.observe``'s arrays."""
    slots = slot_count(params.frontiers, params.meet)
    crop, coarse = params.crop, params.coarse
    low_cand = np.tile(np.array([-1, -1, 0, 0], dtype=np.float32), (slots, 1))
    high_cand = np.tile(np.array([1, 1, 4, 1], dtype=np.float32), (slots, 1))
    low_mate = np.tile(np.array([-1, -1, 0, 0, 0], dtype=np.float32), (params.teammates, 1))
    low_own = np.array([0, 0, -1, -1, 0, 0, 0], dtype=np.float32)
    parts: dict[str, spaces.Space[np.ndarray]] = {
        "local": spaces.Box(0, 1, (4, crop, crop), np.uint8),
        "coarse": spaces.Box(0, 1, (5, coarse, coarse), np.float32),
        "candidates": spaces.Box(low_cand, high_cand, dtype=np.float32),
        "teammates": spaces.Box(low_mate, 1, (params.teammates, TEAMMATE_SIZE), np.float32),
        "own": spaces.Box(low_own, 1, (OWN_SIZE,), np.float32),
        "asked": spaces.Box(0, 1, (1,), np.int8),
    }
    if params.action == "choice":
        parts["action_mask"] = spaces.Box(0, 1, (slots,), np.int8)
    return spaces.Dict(parts)


def action_space(params: PolicyParams) -> spaces.Space[np.ndarray] | spaces.Discrete:
    """A slot (choice), a goal point's fractions (goal_cell) or heading and speed fraction."""
    if params.action == "choice":
        return spaces.Discrete(slot_count(params.frontiers, params.meet))
    if params.action == "goal_cell":
        return spaces.Box(0.0, 1.0, (2,), np.float32)
    return spaces.Box(
        np.array([-np.pi, 0.0], dtype=np.float32), np.array([np.pi, 1.0], dtype=np.float32)
    )


def state_space(side: int, robots: int) -> spaces.Box:
    """The privileged state: the true obstacles and what the base knows, shrunk to
    ``side`` x ``side`` (fractions), then x, y and alive of each possible robot."""
    size = 2 * side * side + STATE_ROBOT * robots
    return spaces.Box(0.0, 1.0, (size,), np.float32)
