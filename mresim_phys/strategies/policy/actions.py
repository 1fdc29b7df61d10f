"""Actions (phase 4, decide): how a ``policy`` robot's action becomes the path it follows.

* ``choice`` (an integer): a slot of the candidate table (``candidates.py``); the robot heads
  for the slot's place on a path of its own planner. ``continue``, or a slot not valid now
  (a policy should respect ``action_mask``), keeps its current target: it stands if it has
  none.
* ``goal_cell`` (two numbers in [0, 1]): a point at those fractions of the map's width and
  height; the robot heads for the reachable cell of its map nearest to it.
* ``velocity`` (two numbers): a heading (radians, the world's x axis, y down) and a speed
  fraction in [0, 1]; the robot drives straight that far this step, its body stopped by
  what it hits, and is asked again on its next step.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from mresim_phys.planning.fields import snap_to_passable
from mresim_phys.strategies.base import Decision, PlanContext, heading_for
from mresim_phys.strategies.policy.candidates import CONTINUE, SNAP, Candidates

Target = tuple[tuple[float, float], tuple[float, float] | None]  # (place, point to face)


def chosen_slot(action: Any, candidates: Candidates) -> int | None:
    """The valid slot a choice ``action`` names, other than ``continue`` (None: continue)."""
    slot = int(np.asarray(action).reshape(-1)[0])
    if slot == CONTINUE or not 0 <= slot < len(candidates.valid) or not candidates.valid[slot]:
        return None
    return slot


def choice_target(action: Any, candidates: Candidates, current: Target | None) -> Target | None:
    """The place a choice ``action`` heads for and the point it then faces (None: stand)."""
    slot = chosen_slot(action, candidates)
    if slot is None:
        return current
    x, y = candidates.points[slot]
    lx, ly = candidates.looks[slot]
    return (float(x), float(y)), None if np.isnan(lx) else (float(lx), float(ly))


def goal_target(action: Any, shape: tuple[int, int]) -> Target:
    """The point a ``goal_cell`` action names (fractions clipped to [0, 1])."""
    fx, fy = np.clip(np.asarray(action, dtype=float).reshape(-1)[:2], 0.0, 1.0)
    return (float(fx * shape[1]), float(fy * shape[0])), None


def toward(context: PlanContext, target: Target | None, action: Any) -> Decision:
    """The decision to head for ``target`` (stand where it is if None): the path to its
    cell if the robot can reach it, else towards the reachable cell nearest to it; its
    ``info`` holds the action (plain numbers)."""
    info = {"action": describe(action)}
    if target is None:
        return Decision(goal=context.view.position, info=info)
    (x, y), look = target
    cell = snap_to_passable(context.passable, (x, y), SNAP)
    if cell is not None and context.field.reachable(*cell):
        path = context.plan_to(*cell)
        if len(path):
            goal = (float(path[-1, 0]), float(path[-1, 1]))
            return Decision(path=path, goal=goal, look_at=look, info=info)
    return heading_for(context, (x, y), look_at=look, info=info)


def describe(action: Any) -> Any:
    """The action as plain numbers."""
    values = np.asarray(action).reshape(-1)
    return int(values[0]) if values.size == 1 else [float(v) for v in values]


def velocity_decision(context: PlanContext, action: Any) -> Decision:
    """Drive straight at the heading and speed fraction ``action`` gives, for one step."""
    view = context.view
    heading, fraction = np.asarray(action, dtype=float).reshape(-1)[:2]
    fraction = float(np.clip(fraction, 0.0, 1.0))
    if fraction == 0.0 or not np.isfinite(heading):
        return Decision(goal=view.position)
    rows, cols = view.belief.shape
    reach = fraction * view.speed
    x = float(np.clip(view.position[0] + reach * np.cos(heading), 0.0, cols))
    y = float(np.clip(view.position[1] + reach * np.sin(heading), 0.0, rows))
    return Decision(path=np.array([[x, y]]), goal=(x, y))
