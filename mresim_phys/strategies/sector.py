"""``sector_rendezvous`` (phase 4, decide): explore sectors, meet neighbours on the boundaries.

After B. L. Wellman, J. de Hoog, S. Dawson, M. Anderson, "Using rendezvous to overcome
communication limitations in multirobot exploration" (IEEE SMC 2011), the study that took
rendezvous out of buildings into open areas: the team divides the open space around the
base into sectors, each robot explores its own, and neighbours meet on the boundary
between their sectors at agreed times instead of near gateways.

* **Sectors**: the robots running the strategy, less those presumed lost, in the team's
  order, split the turn around the base into equal wedges (``span_deg``, 360 by default,
  from ``first_bearing_deg``; a base at an edge of the open space shares less). A robot
  takes the best frontiers (the original's utility) whose centre lies in its wedge,
  searching farther before it looks outside, and joins the greedy auction over all
  frontiers only when its wedge has none left. A lost teammate's wedge is shared out.
* **Meetings**: whenever two ring neighbours are linked, the one first in the team's order
  fixes their next meeting (:class:`SectorMeeting`, sent in its payload): on the ray that
  separates their wedges, at the distance from the base of the nearer of the two (the
  known passable cell nearest that point on its own map), ``meet_interval`` steps later.
  Each robot heads there in time (checked every ``check_interval`` steps), waits until the
  neighbour is linked or ``wait`` steps past the time, then explores on. Linked earlier,
  the meeting is kept (as done) and a new one fixed.

A robot done exploring (as ``frontier``: nothing left or 95 % of the building known) goes
home and keeps no meeting. ``info["sector"]`` is its wedge (bearings, degrees) and
``info["rendezvous"]`` its meeting points (the ``rendezvous`` video layer).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import ClassVar

import numpy as np

from mresim_phys.knowledge.frontiers import Frontiers
from mresim_phys.knowledge.teammates import Payload
from mresim_phys.strategies.appointments import Appointment
from mresim_phys.strategies.base import Decision, PlanContext, RobotView, heading_for, plan_context
from mresim_phys.strategies.catalog import STRATEGIES
from mresim_phys.strategies.frontier import FrontierExploration, default_parts
from mresim_phys.strategies.params import SectorParams, StrategyParams
from mresim_phys.strategies.parts import Allocation, Offer, UtilityRanking
from mresim_phys.types import FloatArray, IntArray


@dataclass(frozen=True)
class SectorMeeting(Payload):
    """A meeting fixed by ``setter`` with ``partner``: where (a boundary point) and when."""

    setter: str
    partner: str
    point: tuple[float, float]
    step: int


@dataclass(frozen=True)
class SectorPayload(Payload):
    """The meetings a robot fixed, sent with its record."""

    meetings: tuple[SectorMeeting, ...]


def wedge(
    order: list[str], name: str, first_deg: float, span_deg: float = 360.0
) -> tuple[float, float]:
    """(start, end) bearings in radians of ``name``'s wedge among ``order`` (the wedges
    share ``span_deg`` degrees from ``first_deg``)."""
    share = math.radians(span_deg) / len(order)
    start = math.radians(first_deg) + order.index(name) * share
    return start, start + share


def in_wedge(bearings: FloatArray, span: tuple[float, float]) -> np.ndarray:
    """Whether each bearing (radians) lies in the wedge ``span``."""
    return np.asarray((bearings - span[0]) % (2 * math.pi) < span[1] - span[0])


@dataclass
class Wedge:
    """A robot's wedge as its last decision set it (shared by its ranking and allocation):
    its bearings ``span`` from the base at ``base`` (None before the first decision), and
    which frontiers of the last ranking lie in it."""

    span: tuple[float, float] = (0.0, 2 * math.pi)
    base: tuple[float, float] | None = None
    inside: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))

    def holds(self, frontiers: Frontiers) -> np.ndarray:
        """Which frontiers (by centroid) lie in the wedge."""
        assert self.base is not None
        dx, dy = (frontiers.centroids - np.asarray(self.base)).T
        return in_wedge(np.arctan2(dy, dx), self.span)


@dataclass
class WedgeRanking:
    """The best reachable frontiers in the robot's wedge (all of them if it has none)."""

    wedge: Wedge
    inner: UtilityRanking

    def candidates(self, frontiers: Frontiers, costs: FloatArray) -> IntArray:
        """The wedge's frontiers by utility, best first (else ``inner``'s candidates)."""
        if self.wedge.base is None:
            return self.inner.candidates(frontiers, costs)
        self.wedge.inside = self.wedge.holds(frontiers)
        mine = self.wedge.inside & np.isfinite(costs)
        if not mine.any():
            return self.inner.candidates(frontiers, costs)
        u = np.where(mine, self.inner.score(frontiers.sizes.astype(float), costs), -np.inf)
        order = np.argsort(-u, kind="stable")
        return order[np.isfinite(u[order])][: self.inner.max_frontiers]

    def settled(
        self, frontiers: Frontiers, costs: FloatArray, candidates: IntArray, limit: float
    ) -> bool:
        """Not while its wedge's frontiers all lie beyond the search horizon ``limit``."""
        inside = self.wedge.inside
        if limit < np.inf and inside.any() and not (inside & np.isfinite(costs)).any():
            return False
        return self.inner.settled(frontiers, costs, candidates, limit)


@dataclass
class WedgeFirst:
    """Its wedge's best frontier; the ``inner`` allocation only outside its wedge."""

    wedge: Wedge
    inner: Allocation

    def choose(self, offer: Offer) -> int:
        """The first candidate if it lies in the wedge, else the inner allocation's."""
        first = offer.candidates[0]
        dx, dy = offer.frontiers.centroids[first] - np.asarray(offer.view.base_position)
        if in_wedge(np.array([math.atan2(dy, dx)]), self.wedge.span)[0]:
            return int(first)
        return self.inner.choose(offer)


@STRATEGIES.register
class SectorRendezvous(FrontierExploration):
    """Each robot explores its sector of the open space and meets its neighbours on the
    sector boundaries at agreed times."""

    name = "sector_rendezvous"
    Params: ClassVar[type[StrategyParams]] = SectorParams
    params: SectorParams

    def __init__(self, params: SectorParams) -> None:
        self.wedge = Wedge()  # its wedge, as its ranking and allocation parts see it
        parts = default_parts(params)
        inner = UtilityRanking(params.max_frontiers, params.candidate_power)
        ranking = WedgeRanking(self.wedge, inner)
        allocation = WedgeFirst(self.wedge, parts.allocation)
        super().__init__(params, replace(parts, ranking=ranking, allocation=allocation))
        self.meetings: dict[str, SectorMeeting] = {}  # partner -> next meeting with it
        self.state = "explore"  # explore / to_meet / wait
        self.met = 0  # meetings kept
        self.speed = 1.0
        self._view: RobotView | None = None
        self._linked: tuple[str, ...] = ()
        self._done = False

    def replan_now(self, step: int, position: tuple[float, float], links: tuple[str, ...]) -> bool:
        """When a neighbour with a meeting comes into reach, at its meeting point, when its
        wait runs out, or (every ``check_interval`` steps) when it must head there now."""
        new = any(name in self.meetings and name not in self._linked for name in links)
        self._linked = links
        meeting = self._next()
        if new or meeting is None:
            return new
        if self.state == "to_meet":
            return math.dist(position, meeting.point) <= self.speed
        if self.state == "wait":
            return step > meeting.step + self.params.wait
        return step % self.params.check_interval == 0 and self._late(step, position, meeting)

    def appointments(self) -> tuple[Appointment, ...]:
        """Its meetings with its neighbours, each kept until ``wait`` steps past its time."""
        wait = self.params.wait
        return tuple(
            Appointment(partner, m.point, m.step, m.step + wait)
            for partner, m in sorted(self.meetings.items())
        )

    def decide(self, view: RobotView) -> Decision:
        """Keep or fix meetings, go to one that is due, else explore its sector."""
        self._view, self.speed = view, view.speed
        order = self._order(view)
        params = self.params
        self.wedge.span = wedge(order, view.name, params.first_bearing_deg, params.span_deg)
        self.wedge.base = view.base_position
        if self._done:  # done exploring: no meetings, unless exploring resumes
            return self._explore(view)
        context = plan_context(view)
        self._settle(view, order, context)
        meeting = self._next()
        if meeting is not None and self._advance(view, meeting):
            return self._send(self._go(view, context, meeting.point))
        return self._explore(view)

    def _explore(self, view: RobotView) -> Decision:
        decision = super().decide(view)
        self._done = decision.done
        if decision.done:
            self.meetings, self.state = {}, "explore"
        return self._send(decision)

    # ---------------------------------------------------------------- sectors

    def _order(self, view: RobotView) -> list[str]:
        """The robots sharing the space: the team's order, less those presumed lost (and
        teammates that said they run another strategy)."""
        order = list(view.team_order) or [view.name]
        others = {
            t.name
            for t in view.teammates.values()
            if t.payload is not None and not isinstance(t.payload, SectorPayload)
        }
        return [n for n in order if n == view.name or (n not in view.lost and n not in others)]

    # ---------------------------------------------------------------- meetings

    def _settle(self, view: RobotView, order: list[str], context: PlanContext) -> None:
        """Drop meetings with the lost; take meetings neighbours fixed; fix new ones."""
        ring = self._neighbours(order, view.name)
        self.meetings = {p: m for p, m in self.meetings.items() if p in ring}
        for partner in sorted(ring):
            record = view.teammates.get(partner)
            if partner not in view.links or record is None:
                continue
            kept = self.meetings.pop(partner, None)  # in contact: the meeting is done
            if kept is not None and self.state != "explore":
                self.met, self.state = self.met + 1, "explore"
            if view.tie_rank(view.name) < view.tie_rank(partner):
                self.meetings[partner] = self._fix(view, order, partner, context)
            elif isinstance(record.payload, SectorPayload):
                for meeting in record.payload.meetings:
                    if meeting.partner == view.name and meeting.step > view.step:
                        self.meetings[partner] = meeting

    @staticmethod
    def _neighbours(order: list[str], name: str) -> set[str]:
        if len(order) < 2:
            return set()
        i = order.index(name)
        return {order[(i - 1) % len(order)], order[(i + 1) % len(order)]}

    def _fix(
        self, view: RobotView, order: list[str], partner: str, context: PlanContext
    ) -> SectorMeeting:
        """The next meeting with ``partner`` on the ray between their wedges."""
        mine, theirs = order.index(view.name), order.index(partner)
        clockwise = (mine + 1) % len(order) == theirs
        bearing = self.wedge.span[1] if clockwise else self.wedge.span[0]
        record = view.teammates[partner]
        base = view.base_position
        radius = min(math.dist(view.position, base), math.dist(record.position, base))
        target = (base[0] + radius * math.cos(bearing), base[1] + radius * math.sin(bearing))
        point = nearest_passable(context, target) or view.position
        return SectorMeeting(view.name, partner, point, view.step + self.params.meet_interval)

    def _next(self) -> SectorMeeting | None:
        """Its earliest meeting."""
        return min(self.meetings.values(), key=lambda m: m.step, default=None)

    def _late(self, step: int, position: tuple[float, float], meeting: SectorMeeting) -> bool:
        return step + math.dist(position, meeting.point) / self.speed >= meeting.step

    def _advance(self, view: RobotView, meeting: SectorMeeting) -> bool:
        """explore -> to_meet -> wait -> explore; whether it heads for (or waits at) it."""
        if self.state == "explore" and self._late(view.step, view.position, meeting):
            self.state = "to_meet"
        if self.state == "to_meet" and math.dist(view.position, meeting.point) <= view.speed:
            self.state = "wait"
        if self.state == "wait" and view.step > meeting.step + self.params.wait:
            del self.meetings[meeting.partner if meeting.setter == view.name else meeting.setter]
            self.state = "explore"  # the neighbour did not come: on with its sector
        return self.state in ("to_meet", "wait")

    def _go(self, view: RobotView, context: PlanContext, point: tuple[float, float]) -> Decision:
        if math.dist(view.position, point) <= view.speed:
            return Decision(goal=view.position)
        return heading_for(context, point, info=context.planner_info())

    def _send(self, decision: Decision) -> Decision:
        mine = tuple(
            m for m in self.meetings.values() if self._view and m.setter == self._view.name
        )
        points = [m.point for m in self.meetings.values()]
        info = {
            **decision.info,
            "sector": tuple(math.degrees(a) for a in self.wedge.span),
            "sector_state": self.state,
        }
        if points:
            info["rendezvous"] = np.array(points, dtype=float)
        return replace(decision, payload=SectorPayload(mine), info=info)


def nearest_passable(
    context: PlanContext, point: tuple[float, float]
) -> tuple[float, float] | None:
    """The centre of the passable cell (on the robot's map) nearest to ``point``."""
    rows, cols = np.nonzero(context.passable)
    if len(rows) == 0:
        return None
    best = int(np.argmin((cols + 0.5 - point[0]) ** 2 + (rows + 0.5 - point[1]) ** 2))
    return float(cols[best] + 0.5), float(rows[best] + 0.5)
