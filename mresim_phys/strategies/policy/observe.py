"""Observations (phase 4, decide): what a ``policy`` robot's policy sees, from its view alone.

A dict of fixed-size arrays (docs/learning.md has each one's meaning and range):

* ``local`` (4, C, C) uint8: the egocentric crop of its belief centred on the robot, the
  world's axes kept (not turned with its heading); channels free, obstacle, unknown,
  frontier (0 or 1); cells beyond the map read as obstacle;
* ``coarse`` (5, G, G) float32: its whole map shrunk to G x G, each cell the fraction of
  free, obstacle, unknown and frontier cells under it (over every ``coarse_stride``-th row
  and column: ``grids.py``), and a fifth channel marking where the robot is;
* ``candidates`` (S, 4) float32: each slot's offset from the robot (dx, dy) and path cost,
  over the map's diagonal, and whether it is valid (``candidates.py``);
* ``teammates`` (T, 5) float32: per teammate in the team's order (the robot left out), its
  last reported offset (over the diagonal), the age of that report (over ``age_scale``,
  at most 1), whether it is linked to the robot now and whether it is presumed lost; a row
  of zeros where the team has no such teammate or never heard of it;
* ``own`` (7,) float32: its position over the map's size, cos and sin of its heading, its
  battery level (1 without a battery), the steps since its data last reached the base (over
  ``age_scale``, at most 1; 1 if never) and whether it is linked to the base now;
* ``asked`` (1,) int8: whether its decision is asked now;
* ``action_mask`` (S,) int8, with choice actions: the slots it may choose (only
  ``continue`` when not asked).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from mresim_phys.knowledge.teammates import BASE_NAME
from mresim_phys.strategies.base import RobotView
from mresim_phys.strategies.params import PolicyParams
from mresim_phys.strategies.policy.candidates import Candidates
from mresim_phys.strategies.policy.grids import coarse_fractions, crop_classes

Observation = dict[str, np.ndarray]
OWN_SIZE = 7
TEAMMATE_SIZE = 5


def observe(
    view: RobotView,
    candidates: Candidates,
    params: PolicyParams,
    team: Sequence[str],
    asked: bool,
) -> Observation:
    """The observation of ``view`` (module docstring); ``team`` the robots' names in order."""
    belief = view.belief
    scale = float(np.hypot(*belief.shape))
    obs: Observation = {
        "local": local_crop(belief, view.position, params.crop),
        "coarse": coarse_view(belief, view.position, params.coarse, params.coarse_stride),
        "candidates": candidate_rows(candidates, view.position, scale),
        "teammates": teammate_rows(view, team, params, scale),
        "own": own_row(view, params.age_scale),
        "asked": np.array([int(asked)], dtype=np.int8),
    }
    if params.action == "choice":
        obs["action_mask"] = candidates.valid.astype(np.int8)
    return obs


def local_crop(belief: np.ndarray, position: tuple[float, float], side: int) -> np.ndarray:
    """The (4, side, side) crop centred on the robot's cell; beyond the map: obstacle."""
    r0, c0 = int(position[1]) - side // 2, int(position[0]) - side // 2
    crop: np.ndarray = crop_classes(belief, r0, c0, side)
    return crop


def coarse_view(
    belief: np.ndarray, position: tuple[float, float], side: int, stride: int
) -> np.ndarray:
    """(5, side, side) float32: the class fractions under each coarse cell (over every
    ``stride``-th row and column), and the robot."""
    out = np.zeros((5, side, side), dtype=np.float32)
    out[:4] = coarse_fractions(belief, side, stride)
    rows, cols = belief.shape
    r = min(max(int(position[1] * side // rows), 0), side - 1)
    c = min(max(int(position[0] * side // cols), 0), side - 1)
    out[4, r, c] = 1.0
    return out


def candidate_rows(
    candidates: Candidates, position: tuple[float, float], scale: float
) -> np.ndarray:
    """(S, 4): offset, cost (over ``scale``, at most 4) and validity of each slot."""
    valid = candidates.valid
    rows = np.zeros((len(valid), 4), dtype=np.float32)
    rows[:, 0] = (candidates.points[:, 0] - position[0]) / scale
    rows[:, 1] = (candidates.points[:, 1] - position[1]) / scale
    costs = np.where(np.isfinite(candidates.costs), candidates.costs / scale, 4.0)
    rows[:, 2] = np.minimum(costs, 4.0)
    rows[:, 3] = valid
    rows[~valid, :3] = 0.0
    return rows


def teammate_rows(
    view: RobotView, team: Sequence[str], params: PolicyParams, scale: float
) -> np.ndarray:
    """(T, 5): the teammates' last reports, in the team's order (module docstring)."""
    rows = np.zeros((params.teammates, TEAMMATE_SIZE), dtype=np.float32)
    others = [name for name in team if name != view.name][: params.teammates]
    lost, linked = view.lost, set(view.links)
    x, y = view.position
    for k, name in enumerate(others):
        info = view.teammates.get(name)
        if info is None or name == BASE_NAME:
            continue
        age = min((view.step - info.step) / params.age_scale, 1.0)
        rows[k] = (
            (info.position[0] - x) / scale, (info.position[1] - y) / scale, age,
            name in linked, name in lost,
        )  # fmt: skip
    return rows


def own_row(view: RobotView, age_scale: float) -> np.ndarray:
    """(7,): position, heading, battery, base contact age and link (module docstring)."""
    rows, cols = view.belief.shape
    battery = view.features.get("battery")  # the level left (faults/battery.py), if any
    since = view.step - view.base_contact
    contact = 1.0 if view.base_contact < 0 else min(since / age_scale, 1.0)
    return np.array(
        [
            view.position[0] / cols, view.position[1] / rows, np.cos(view.heading),
            np.sin(view.heading), 1.0 if battery is None else float(battery), contact,
            float(BASE_NAME in view.links),
        ],
        dtype=np.float32,
    )  # fmt: skip
