"""A strategy for the rendezvous accounting tests: a robot that keeps one fixed meeting.

Imported by name (``meeting_plugins:GoMeet``); pytest puts this folder on ``sys.path``.
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np

from mresim_phys.strategies.appointments import Appointment
from mresim_phys.strategies.base import Decision, RobotView
from mresim_phys.strategies.params import StrategyParams
from mresim_phys.strategies.random_walk import RandomWalk


class GoMeetParams(StrategyParams):
    """The meeting: partner, this robot's point, the agreed step, the wait, and the step
    the robot sets out (it stands still before)."""

    replan_interval: int = 1
    partner: str
    point: tuple[float, float]
    step: int
    wait: int
    depart: int = 0


class GoMeet(RandomWalk):
    """Waits until ``depart``, then drives straight to its point and stays there."""

    Params: ClassVar[type[StrategyParams]] = GoMeetParams  # type: ignore[misc]
    params: GoMeetParams  # type: ignore[assignment]

    def appointments(self) -> tuple[Appointment, ...]:
        p = self.params
        return (Appointment(p.partner, p.point, p.step, p.step + p.wait),)

    def decide(self, view: RobotView) -> Decision:
        p = self.params
        if view.step < p.depart or math.dist(view.position, p.point) <= view.speed:
            return Decision(goal=view.position)
        return Decision(path=np.array([view.position, p.point]), goal=p.point)
