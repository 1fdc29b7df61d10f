"""``role_based`` (phase 4, decide): explorer / relay pairs that meet at agreed rendezvous points.

The original's ``RoleBasedExploration`` (J. de Hoog, S. Cameron, A. Visser, "Role-based
autonomous multi-robot exploration", 2009; "Dynamic team hierarchies in communication-
limited multi-robot exploration", 2010) with its *basic* single-point rendezvous. The
team's hierarchy pairs robots: an explorer's ``parent`` is its relay (``role: relay``),
the relay's parent the base.

* The **explorer** explores greedily (as ``frontier``). Whenever it is linked with its
  relay it proposes their next meeting (:class:`Rendezvous`, sent with its record). Both
  decide at every step of contact: the relay takes the proposal the last exchange
  brought, and the explorer, seeing that exchange succeeded, binds itself to the same
  one, so the pair never parts holding different meetings (a proposal whose exchange
  failed binds neither). The
  point is its frontier target if that lies more than ``MIN_RV_DISTANCE`` cells away,
  else where it stands (``rendezvous: improved``: the best skeleton junction near that
  frontier, ``meetings.improved_point``); the time is ``now + max(60, the relay's trip
  to the base and on to the point, its own trip to the frontier and on to the point +
  75)`` (straight lines
  at its own speed; the original uses path lengths). Every ``check_interval`` steps it
  checks whether it must head back to be there in time; at the point it waits for the
  relay until ``wait`` steps after the agreed time; a relay that has not come (late,
  failed) leaves it to report in person: it returns to the base, then explores on.
* The **relay** holds still for its first :data:`START_HOLD` steps (state ``start``, as the
  original's relays wait in ``Initial``), so that its explorer's first agreement reaches
  it before they part. It takes the agreement whenever it is linked with its explorer, carries
  what it got to the base (until its data has reached the base), goes to the point and
  waits until ``wait + backup_wait`` steps after the agreed time. An explorer that never
  comes is given up: the relay explores greedily until it meets its explorer again.

A robot outside such a pair explores as ``frontier`` does. The state each is in shows in
its decision's ``info`` (``rv_state``).
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import ClassVar

from mresim_phys.knowledge.teammates import Payload, TeammateInfo
from mresim_phys.strategies.appointments import Appointment
from mresim_phys.strategies.base import Decision, RobotView, heading_for, plan_context
from mresim_phys.strategies.catalog import STRATEGIES
from mresim_phys.strategies.frontier import FrontierExploration
from mresim_phys.strategies.meetings import MeetingPlanner, Rendezvous, overdue
from mresim_phys.strategies.params import RoleBasedParams, StrategyParams
from mresim_phys.types import FloatArray

START_HOLD = 2  # steps a relay without an agreement holds still at the start (the original)


@STRATEGIES.register
class RoleBased(FrontierExploration):
    """Explorers explore and meet their relays; relays shuttle between them and the base."""

    name = "role_based"
    Params: ClassVar[type[StrategyParams]] = RoleBasedParams
    params: RoleBasedParams

    def __init__(self, params: RoleBasedParams) -> None:
        super().__init__(params)
        self.meeting: Rendezvous | None = None  # the meeting that binds it
        self.proposal: Rendezvous | None = None  # explorer: the next meeting it proposes
        self.state = "explore"
        self.partner: str | None = None  # its relay (explorer) or explorer (relay)
        self.speed = 1.0
        self._is_relay = False
        self._linked = False  # its partner was linked at the last check
        self.planner = MeetingPlanner(params.rendezvous, params.wait)  # its rendezvous part

    def replan_now(self, step: int, position: tuple[float, float], links: tuple[str, ...]) -> bool:
        """When its state would change: its partner comes into reach (multi-point: is in
        reach, as through walls it may be all along), it arrives at the meeting point,
        its wait runs out, the base comes into reach while it heads there,
        or (checked every ``check_interval`` steps) it must head for the meeting now."""
        if self.partner is None:
            return False
        was_linked, self._linked = self._linked, self.partner in links
        if self._linked or was_linked:  # agreements are exchanged at every step of contact
            return True
        meeting = self.meeting
        if self.state == "start":
            return True
        if meeting is None and self.state == "explore":
            return False
        if self.state in ("carry", "home"):
            return "base" in links
        assert meeting is not None
        # multi-point: the partners may be linked from their own points (through walls)
        # all along, so being linked, not the link's appearance, ends a wait (and an
        # explorer's trip to its point)
        linked = self.params.rendezvous == "multi_point" and self.partner in links
        if self.state == "to_rv":
            arrived = math.dist(position, self._my_point(meeting)) <= self.speed
            return arrived or (linked and not self._is_relay)
        if self.state == "wait":
            return linked or step > meeting.step + self._patience(meeting)
        due = step % self.params.check_interval == 0 and not self._is_relay
        return due and self._late(step, position, meeting)

    def decide(self, view: RobotView) -> Decision:
        """The explorer's or the relay's rule, by the robot's place in the hierarchy."""
        self.speed = view.speed
        if view.role == "relay" and view.children:
            self.partner, self._is_relay = view.children[0], True
            decision = self._relay(view)
        elif view.parent not in (None, "base"):
            self.partner = view.parent
            decision = self._explorer(view)
        else:
            decision = super().decide(view)
        return replace(decision, info={**decision.info, "rv_state": self.state, **self._views()})

    def appointments(self) -> tuple[Appointment, ...]:
        """The meeting that binds it: with its partner at its own point, kept until its
        patience runs out (``wait`` past the agreed time; a relay without a backup meeting
        ``backup_wait`` more)."""
        meeting, partner = self.meeting, self.partner
        if meeting is None or partner is None:
            return ()
        closes = meeting.step + self._patience(meeting)
        return (Appointment(partner, self._my_point(meeting), meeting.step, closes),)

    def _views(self) -> dict[str, FloatArray]:
        """What the rendezvous layers draw: the agreed points, and (multi-point) the
        potential points and those linked through walls."""
        views = {} if self.meeting is None else {"rendezvous": self.meeting.points()}
        return {**views, **self.planner.views()}

    def _my_point(self, meeting: Rendezvous) -> tuple[float, float]:
        return meeting.relay_at if self._is_relay else meeting.point

    def _patience(self, meeting: Rendezvous) -> int:
        """Steps past the agreed time it waits: ``wait``, and a relay without a backup
        meeting ``backup_wait`` more before it gives its explorer up."""
        extra = self.params.backup_wait if self._is_relay and meeting.backup is None else 0
        return self.params.wait + extra

    def _late(self, step: int, position: tuple[float, float], meeting: Rendezvous) -> bool:
        """Whether the trip to the meeting point would end at or after the agreed time."""
        return step + math.dist(position, meeting.point) / self.speed >= meeting.step

    # ---------------------------------------------------------------- explorer

    def _explorer(self, view: RobotView) -> Decision:
        relay = view.parent or ""
        explored: Decision | None = None
        sent, self.proposal = self.proposal, None
        if relay in view.links:  # together: agree the next meeting, explore on
            explored = super().decide(view)
            # the exchange that links them carried what it proposed last, and the relay
            # (deciding at every step of contact) takes it now: it binds both
            stale = sent is None and overdue(self.meeting, view.step)
            self.state, self.meeting = "explore", sent or (None if stale else self.meeting)
            self.proposal = self.planner.agree(view, relay, explored)
            if stale:  # met after the agreed time: stay until the relay has the new one
                return Decision(goal=view.position, payload=self.proposal)
        meeting = self.meeting
        if meeting is not None:
            self._advance_explorer(view, meeting)
        if self.meeting is not None and self.state in ("to_rv", "wait"):
            return self._go(view, self.meeting.point, self.proposal)
        if self.state == "home":
            return self._go(view, view.base_position, None)
        explored = explored or super().decide(view)
        return replace(explored, payload=self.proposal)

    def _advance_explorer(self, view: RobotView, meeting: Rendezvous) -> None:
        """explore -> to_rv -> wait -> (relay met: explore) or (relay late: home -> explore)."""
        if self.state == "explore" and self._late(view.step, view.position, meeting):
            self.state = "to_rv"
        if self.state == "to_rv" and math.dist(view.position, meeting.point) <= view.speed:
            self.state = "wait"
        if self.state == "wait" and view.step > meeting.step + self.params.wait:
            self.state = "home" if meeting.backup is None else "to_rv"
            self.meeting = meeting.backup or meeting
        if self.state == "home" and view.base_contact >= view.step - 1:
            self.state, self.meeting = "explore", None

    # ---------------------------------------------------------------- relay

    def _relay(self, view: RobotView) -> Decision:
        """start -> carry -> to_rv -> wait -> (explorer met: carry) or (given up: explore)."""
        mate = self._explorer_record(view)
        if mate is not None and mate.name in view.links:
            agreement = self.agreement_of(mate)
            stale = agreement is None and overdue(self.meeting, view.step)
            self.meeting = agreement or (None if stale else self.meeting)
            self.state = "carry"
            if stale:  # met after the agreed time: stay until the explorer's proposal comes
                return Decision(goal=view.position)
        meeting = self.meeting
        if self.state == "carry" and view.base_contact >= view.step - 1:
            self.state = "to_rv" if meeting is not None else "explore"
        if meeting is not None:
            self._advance_relay(view, meeting)
        if meeting is None and self.state in ("explore", "start"):
            self.state = "start" if view.step <= START_HOLD else "explore"
            if self.state == "start":
                return Decision(goal=view.position)
        if self.state == "carry":
            return self._go(view, view.base_position, None)
        if self.meeting is not None and self.state in ("to_rv", "wait"):
            return self._go(view, self.meeting.relay_at, None)
        return super().decide(view)

    def _advance_relay(self, view: RobotView, meeting: Rendezvous) -> None:
        if self.state == "to_rv" and math.dist(view.position, meeting.relay_at) <= view.speed:
            self.state = "wait"
        if self.state == "wait" and view.step > meeting.step + self._patience(meeting):
            if meeting.backup is not None:  # on to the backup meeting
                self.state, self.meeting = "to_rv", meeting.backup
            else:
                self.state, self.meeting = "explore", None  # its explorer never came

    def agreement_of(self, record: TeammateInfo) -> Rendezvous | None:
        """The meeting agreement a teammate's record carries (None: none)."""
        return record.payload if isinstance(record.payload, Rendezvous) else None

    def _explorer_record(self, view: RobotView) -> TeammateInfo | None:
        records = [view.teammates[name] for name in view.children if name in view.teammates]
        return records[0] if records else None

    # ---------------------------------------------------------------- moving

    def _go(self, view: RobotView, point: tuple[float, float], payload: Payload | None) -> Decision:
        """A path to ``point`` (as near as the robot's map lets it get); none when it is
        there already (waiting costs no search)."""
        if math.dist(view.position, point) <= view.speed:
            return Decision(goal=view.position, payload=payload)
        context = plan_context(view)
        info = context.planner_info()
        path = context.plan_to(math.floor(point[1]), math.floor(point[0]))
        if len(path) == 0:  # not a cell it can stand on: as near as it can get
            return heading_for(context, point, payload=payload, info=info)
        goal = (float(path[-1, 0]), float(path[-1, 1]))
        return Decision(path=path, goal=goal, payload=payload, info=info)
