"""``random_walk`` (phase 4, decide): go to a random reachable known-free cell nearby, repeatedly.

A baseline for comparisons. :func:`random_step` is the original's ``RandomWalk``
step, which its frontier exploration takes for its first cycles (and after
errors): keep the heading or turn a little, and move one step's length if the
straight line stays in known free space clear of walls. Draws come from the
robot's own ``strategy`` stream, so a run is reproducible and robots never
disturb each other's draws.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import ClassVar

import numpy as np

from mresim_phys.plugin import Plugin
from mresim_phys.strategies.base import Decision, PlanContext, RobotView, plan_context
from mresim_phys.strategies.catalog import STRATEGIES
from mresim_phys.strategies.params import RandomWalkParams, StrategyParams

Point = tuple[float, float]

# The original's RandomWalk: heading changes and their odds (out of 26).
TURNS_DEG = np.array([-45.0, -22.5, 0.0, 22.5, 45.0])
TURN_ODDS = np.array([1, 2, 20, 2, 1]) / 26
STEP_TRIES = 50  # tries at one step length before giving up
MIN_STEP = 3.0  # cells: a failed try shortens the step by one cell down to this


def random_step(
    view: RobotView,
    context: PlanContext,
    fits: Callable[[Point, Point], bool] | None = None,
    heading: float | None = None,
) -> Decision | None:
    """One random-walk step from the robot's own stream, or None if no try fits.

    The heading (the robot's own, unless ``heading`` is given) changes by -45, -22.5,
    0, +22.5 or +45 degrees (odds 1:2:20:2:1); the step is the robot's speed, one cell
    shorter after each failed try (at least 3 cells). A try fits if every cell on the
    straight line is passable (known free and the robot's clearance away from known
    walls) and ``fits(start, end)``, if given.
    """
    passable = context.passable
    x, y = view.position
    length = view.speed
    ahead = view.heading if heading is None else heading
    for _ in range(STEP_TRIES):
        turn = float(np.radians(view.rng.choice(TURNS_DEG, p=TURN_ODDS)))
        end = (x + length * np.cos(ahead + turn), y + length * np.sin(ahead + turn))
        if segment_passable(passable, (x, y), end) and (fits is None or fits((x, y), end)):
            path = np.array([[x, y], end])
            return Decision(path=path, goal=(float(end[0]), float(end[1])))
        length = max(length - 1.0, min(MIN_STEP, view.speed))
    return None


def segment_passable(
    passable: np.ndarray, start: tuple[float, float], end: tuple[float, float]
) -> bool:
    """True if every cell the straight segment crosses (sampled at quarter cells) is passable."""
    n = max(int(np.ceil(4 * np.hypot(end[0] - start[0], end[1] - start[1]))), 1)
    t = np.linspace(0.0, 1.0, n + 1)
    cols = np.floor(start[0] + t * (end[0] - start[0])).astype(np.intp)
    rows = np.floor(start[1] + t * (end[1] - start[1])).astype(np.intp)
    rows_n, cols_n = passable.shape
    if rows.min() < 0 or cols.min() < 0 or rows.max() >= rows_n or cols.max() >= cols_n:
        return False
    return bool(passable[rows, cols].all())


@STRATEGIES.register
class RandomWalk(Plugin):
    """Pick a uniformly random reachable cell within ``distance`` path cost; go there."""

    name = "random_walk"

    Params: ClassVar[type[StrategyParams]] = RandomWalkParams
    params: RandomWalkParams

    def __init__(self, params: RandomWalkParams) -> None:
        self.params = params

    def decide(self, view: RobotView) -> Decision:
        """A path to a random cell reachable within ``distance``."""
        context = plan_context(view)
        costs = context.field.costs
        rows, cols = np.nonzero(np.isfinite(costs) & (costs <= self.params.distance))
        if len(rows) == 0:
            return Decision()
        pick = int(view.rng.integers(len(rows)))
        row, col = int(rows[pick]), int(cols[pick])
        return Decision(
            path=context.plan_to(row, col),
            goal=(col + 0.5, row + 0.5),
            info=context.planner_info(),
        )
