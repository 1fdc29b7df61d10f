"""A strategy whose worker process dies, for the sweep tests of lost runs.

Imported by name (``sweep_crash_plugins:Dies``) in the sweep's worker processes, which
start with the test process's ``sys.path`` (pytest puts this folder on it). Never run it
in the test process itself: it SIGKILLs the process it runs in.
"""

from __future__ import annotations

import os
import signal

from mresim_phys.strategies.base import Decision, RobotView
from mresim_phys.strategies.random_walk import RandomWalk


class Dies(RandomWalk):
    """A random walk whose process is killed at step 3 (the OOM killer, say)."""

    def decide(self, view: RobotView) -> Decision:
        if view.step >= 3:
            os.kill(os.getpid(), signal.SIGKILL)
        return super().decide(view)
