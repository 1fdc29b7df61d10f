"""``utility_return`` (phase 4, decide): greedy frontier exploration that goes home to report.

The original's ``UtilityExploration`` (J. Spirin, S. Cameron, J. de Hoog, "Time
preference for information in multi-agent exploration with limited communication",
TAROS 2013): a robot explores as ``frontier`` does, but at every decision out of
contact with the base it weighs what the base knows against what only it carries:

    r = B / (B + N)

with ``B`` the cells of its map it believes the base knows (those it held the last
time its data reached the base) and ``N`` the cells it must still deliver (found
since, plus any it took over from teammates). When ``r < target_ratio`` it heads for
the base and explores again once its data has reached the base (it is in contact).

Robots that meet hand over the duty to deliver (ownership of undelivered cells):
each sends its ``N`` and its distance to the base with its record
(:class:`DeliveryPayload`). After an exchange both hold the same map, so the cells
the nearer robot received already count in its own ``N``; the one farther from the
base by more than ``handover_margin`` cells drops its ``N`` (it has handed them
over), and the nearer robot carries the team's news home (an opportunistic relay).
Both decide from the same two records, so they agree. Distances to the base are
straight lines (the original uses path lengths). ``N`` counts every cell its map
gained since the last delivery, received ones too: a robot cannot tell which of them
a teammate in contact with the base has delivered already.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import ClassVar

import numpy as np

from mresim_phys.knowledge.teammates import Payload, TeammateInfo
from mresim_phys.strategies.appointments import BASE, Appointment
from mresim_phys.strategies.base import Decision, RobotView, heading_for
from mresim_phys.strategies.base import plan_context as make_context
from mresim_phys.strategies.catalog import STRATEGIES
from mresim_phys.strategies.frontier import FrontierExploration
from mresim_phys.strategies.params import StrategyParams, UtilityReturnParams
from mresim_phys.types import FREE, FloatArray

RETURN_GRACE = 20  # steps past its expected arrival that a return is kept (docs/rendezvous.md)


@dataclass(frozen=True)
class DeliveryPayload(Payload):
    """What a ``utility_return`` robot tells its teammates: cells it must still deliver,
    its straight-line distance to the base, and the step it said so."""

    undelivered: int
    to_base: float
    step: int


@STRATEGIES.register
class UtilityReturn(FrontierExploration):
    """Greedy frontier exploration that returns to report when r = B / (B + N) drops."""

    name = "utility_return"
    Params: ClassVar[type[StrategyParams]] = UtilityReturnParams
    params: UtilityReturnParams

    def __init__(self, params: UtilityReturnParams) -> None:
        super().__init__(params)
        self.delivered = 0  # B: map cells held when its data last reached the base
        self.handed = 0  # cells a teammate took over (no longer its to deliver)
        self.returning = False
        self.trip: Appointment | None = None  # the return it set out on (its meeting with the base)

    def appointments(self) -> tuple[Appointment, ...]:
        """The return under way: a meeting with the base at the end of its path home, at
        its expected arrival (path length over speed); any link with the base from setting
        out to :data:`RETURN_GRACE` steps past the arrival keeps it."""
        return () if self.trip is None else (self.trip,)

    def decide(self, view: RobotView) -> Decision:
        """Explore, or head home while the ratio is below target and the base is out of reach."""
        known = int(np.count_nonzero(view.belief == FREE))
        to_base = math.dist(view.position, view.base_position)
        if view.base_contact >= view.step - 1:  # its data reached the base: all delivered
            self.delivered, self.handed = known, 0
            self.returning = False
        else:
            self._hand_over(view, known, to_base)
            self.returning = self.ratio(known) < self.params.target_ratio
        payload = DeliveryPayload(self.undelivered(known), to_base, view.step)
        if self.returning:
            home = self._go_home(view, payload)
            if self.trip is None:
                self.trip = return_trip(view, home.path, home.goal)
            return home
        self.trip = None
        return replace(super().decide(view), payload=payload)

    def undelivered(self, known: int) -> int:
        """N: cells its map gained since the last delivery, less those handed over."""
        return max(known - self.delivered - self.handed, 0)

    def ratio(self, known: int) -> float:
        """r = B / (B + N) (1 while there is nothing to deliver)."""
        undelivered = self.undelivered(known)
        total = self.delivered + undelivered
        return 1.0 if undelivered == 0 or total == 0 else self.delivered / total

    def _hand_over(self, view: RobotView, known: int, to_base: float) -> None:
        """Hand its undelivered cells to a linked teammate nearer the base (by more than
        ``handover_margin``): after the exchange that teammate holds them too."""
        margin = self.params.handover_margin
        for mate in self._linked_reports(view):
            report = mate.payload
            assert isinstance(report, DeliveryPayload)
            if report.to_base < to_base - margin:
                self.handed = max(known - self.delivered, 0)

    def _linked_reports(self, view: RobotView) -> list[TeammateInfo]:
        """Records of the teammates linked at the last exchange that carry a delivery
        report (the one from their last decision), by name."""
        mates = (view.teammates.get(name) for name in view.links)
        fresh = [
            m
            for m in mates
            if m is not None and isinstance(m.payload, DeliveryPayload) and m.step >= view.step - 1
        ]
        return sorted(fresh, key=lambda m: m.name)

    def _go_home(self, view: RobotView, payload: DeliveryPayload) -> Decision:
        """A path to the base (as near as its map lets it get), not done: it explores
        again once its data has reached the base."""
        context = make_context(view)
        info = {"returning": True, **context.planner_info()}
        return heading_for(context, view.base_position, info=info, payload=payload)


def return_trip(view: RobotView, path: FloatArray, goal: tuple[float, float] | None) -> Appointment:
    """A return setting out now along ``path`` to ``goal``: the meeting with the base."""
    points = np.vstack((np.asarray(view.position, dtype=float).reshape(1, 2), path))
    length = float(np.hypot(*np.diff(points, axis=0).T).sum()) if len(path) else 0.0
    step = view.step + math.ceil(length / view.speed)
    end = goal if goal is not None else view.position
    point = (float(end[0]), float(end[1]))
    return Appointment(BASE, point, step, step + RETURN_GRACE, opens=view.step)
