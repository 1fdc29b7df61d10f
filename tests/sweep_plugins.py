"""A strategy that breaks, for the sweep tests: a run that raises is recorded, the sweep goes on.

Imported by name (``sweep_plugins:Breaks``) in the test process and in the sweep's
worker processes, which start with the test process's ``sys.path`` (pytest puts this
folder on it).
"""

from __future__ import annotations

from mresim_phys.strategies.base import Decision, RobotView
from mresim_phys.strategies.random_walk import RandomWalk


class Breaks(RandomWalk):
    """A random walk whose decide raises at step 3 (a bug in a user's strategy)."""

    def decide(self, view: RobotView) -> Decision:
        if view.step >= 3:
            raise RuntimeError("this strategy has a bug")
        return super().decide(view)
