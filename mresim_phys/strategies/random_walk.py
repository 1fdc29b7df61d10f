"""``random_walk`` (phase 4, decide): go to a random reachable known-free cell nearby, repeatedly.

A baseline for comparisons (the original uses random steps for its first cycles
and after errors). Draws come from the robot's own ``strategy`` stream, so a
run is reproducible and robots never disturb each other's draws.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np
from pydantic import Field

from mresim_phys.plugin import Plugin
from mresim_phys.strategies.base import (
    STRATEGIES,
    Decision,
    RobotView,
    StrategyParams,
    plan_context,
)


class RandomWalkParams(StrategyParams):
    """How far a random walk leg may go."""

    replan_interval: int = Field(15, ge=1, description="Steps between new random goals.")
    distance: float = Field(30.0, gt=0, description="Longest path (cells) to a random goal.")


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
