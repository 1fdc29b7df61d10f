"""Strategies for the run-health tests: a robot that parks, one that quits with a reason,
one that shuttles.

Imported by name (``health_plugins:Parked``); pytest puts this folder on ``sys.path``.
"""

from __future__ import annotations

import numpy as np

from mresim_phys.strategies.base import Decision, RobotView
from mresim_phys.strategies.random_walk import RandomWalk


class Parked(RandomWalk):
    """Never moves and never says it is done (a strategy that lost its targets)."""

    def decide(self, view: RobotView) -> Decision:
        return Decision()


class QuitsAtFive(RandomWalk):
    """A random walk that declares itself done at step 5, saying why, and stays."""

    def decide(self, view: RobotView) -> Decision:
        if view.step >= 5:
            return Decision(done=True, info={"reason": "told to quit"})
        return super().decide(view)


class Shuttles(RandomWalk):
    """Drives back and forth between where it starts and 6 cells to its right, forever:
    it never idles and, once it has seen what there is to see from there, learns nothing."""

    def decide(self, view: RobotView) -> Decision:
        x, y = view.position
        start = getattr(self, "start", None)
        if start is None:
            start = self.start = (x, y)
        at_start = (x - start[0]) ** 2 + (y - start[1]) ** 2 < 1.0
        goal = (start[0] + 6.0, start[1]) if at_start else start
        return Decision(path=np.array([view.position, goal]), goal=goal)
