"""Strategies for the run-health tests: a robot that parks, one that quits with a reason.

Imported by name (``health_plugins:Parked``); pytest puts this folder on ``sys.path``.
"""

from __future__ import annotations

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
