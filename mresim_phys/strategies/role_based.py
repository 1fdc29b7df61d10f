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
  point is its frontier target if that lies more than :data:`MIN_RV_DISTANCE` cells away,
  else where it stands (``rendezvous: improved``: the best skeleton junction near that
  frontier, :func:`improved_point`); the time is ``now + max(60, the relay's trip to the base and on
  to the point, its own trip to the frontier and on to the point + 75)`` (straight lines
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
from dataclasses import dataclass, replace
from typing import ClassVar, Literal

import numpy as np
from pydantic import Field

from mresim_phys.knowledge.teammates import Payload, TeammateInfo
from mresim_phys.strategies.base import (
    STRATEGIES,
    Decision,
    RobotView,
    StrategyParams,
    heading_for,
    plan_context,
)
from mresim_phys.strategies.frontier import FrontierExploration, FrontierParams
from mresim_phys.strategies.rendezvous import MultiPoint, relay_point
from mresim_phys.types import FloatArray

MIN_RV_DISTANCE = 25.0  # cells: a nearer frontier is no meeting point (the original's 25 px)
IMPROVED_REACH = 600.0  # cells: junctions farther from the frontier are no candidates
IMPROVED_CANDIDATES = 4  # the nearest junctions scored (the original's 4)
MIN_MEETING_DELAY = 60  # steps: the earliest meeting after an agreement (the original)
EXPLORE_TIME = 75  # steps the explorer gets at its frontier (FRONTIER_MIN_EXPLORE_TIME)
RV_REPLAN_INTERVAL = 15  # steps: multi-point points are recomputed at most this often
START_HOLD = 2  # steps a relay without an agreement holds still at the start (the original)


class RoleBasedParams(FrontierParams):
    """Greedy frontier exploration's parameters and the rendezvous rules (original values)."""

    wait: int = Field(60, ge=0, description="Steps to wait at the point after the agreed time.")
    backup_wait: int = Field(
        60, ge=0, description="Relay: further steps it waits before it gives its explorer up."
    )
    check_interval: int = Field(
        2, ge=1, description="Steps between checks whether to head for the meeting."
    )
    rendezvous: Literal["basic", "improved", "multi_point"] = Field(
        "basic",
        description=(
            "Meeting points: 'basic' (the frontier target, else where the explorer stands),"
            " 'improved' (the best skeleton junction near the frontier, as the original's"
            " useImprovedRendezvous) or 'multi_point' (the improved point for the explorer"
            " and, for the relay, the point linked with it through walls that is nearest the"
            " base's range, with a backup meeting where they agreed: the original's"
            " RVThroughWalls, SSRR 2014)."
        ),
    )


@dataclass(frozen=True)
class Rendezvous(Payload):
    """An explorer's agreement with its relay: where and when they meet next.

    ``point`` is the explorer's; ``relay_point`` the relay's when they differ (multi-point:
    linked through walls); ``backup`` the meeting both fall back to when the other has
    not come by the end of the wait (multi-point). Unset fields cost no bytes."""

    point: tuple[float, float]
    step: int
    relay_point: tuple[float, float] | None = None
    backup: Rendezvous | None = None

    @property
    def relay_at(self) -> tuple[float, float]:
        """Where the relay waits."""
        return self.point if self.relay_point is None else self.relay_point

    def points(self) -> FloatArray:
        """The agreed points (explorer's, relay's, backup's) as (k, 2), for the layers."""
        pts = [self.point, self.relay_at] + ([self.backup.point] if self.backup else [])
        return np.array(pts, dtype=float)


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
        self._multi: tuple[int, MultiPoint] | None = None  # (step, last multi-point choice)

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

    def _views(self) -> dict[str, FloatArray]:
        """What the rendezvous layers draw: the agreed points, and (multi-point) the
        potential points and those linked through walls."""
        views = {} if self.meeting is None else {"rendezvous": self.meeting.points()}
        if self._multi is not None:
            views["rv_candidates"] = self._multi[1].candidates
            views["rv_through_walls"] = self._multi[1].through_walls
        return views

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
            self.proposal = self._agree(view, relay, explored)
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

    def _agree(self, view: RobotView, relay: str, explored: Decision) -> Rendezvous:
        """The next meeting: its frontier target (else here), at the original's time."""
        frontier = view.position if explored.done or explored.goal is None else explored.goal
        near = math.dist(frontier, view.position) <= MIN_RV_DISTANCE
        point = view.position if near else frontier
        if self.params.rendezvous in ("improved", "multi_point") and not near:
            point = improved_point(view, frontier) or point
        point = (float(point[0]), float(point[1]))
        multi = self.params.rendezvous == "multi_point"
        theirs = self._relay_point(view, point) if multi else point
        record = view.teammates.get(relay)
        relay_at = record.position if record is not None else view.position
        base = view.base_position
        relay_trip = math.dist(relay_at, base) + math.dist(base, theirs)
        own_trip = math.dist(view.position, frontier) + math.dist(frontier, point)
        delay = max(
            MIN_MEETING_DELAY, relay_trip / view.speed, own_trip / view.speed + EXPLORE_TIME
        )
        step = view.step + math.ceil(delay)
        if not multi:
            return Rendezvous(point, step)
        return Rendezvous(point, step, theirs, self._backup(view, point, theirs, step))

    def _relay_point(self, view: RobotView, point: tuple[float, float]) -> tuple[float, float]:
        """Multi-point: the relay's point for the explorer's ``point`` (recomputed at most
        every :data:`RV_REPLAN_INTERVAL` steps or when the explorer's point moved)."""
        last = self._multi
        fresh = last is not None and view.step - last[0] < RV_REPLAN_INTERVAL
        if last is None or not fresh or math.dist(last[1].explorer, point) > MIN_RV_DISTANCE:
            context = plan_context(view)
            reach = view.comm_range
            choice = relay_point(
                view.belief, context.passable, context.passable_box, point,
                view.base_position, reach,
            )  # fmt: skip
            self._multi = last = (view.step, choice)
        return last[1].relay

    def _backup(
        self, view: RobotView, point: tuple[float, float], theirs: tuple[float, float], step: int
    ) -> Rendezvous:
        """The backup meeting: where the pair stands now (they are linked here), once the
        wait is over and both could have walked there from their points."""
        here = (float(view.position[0]), float(view.position[1]))
        trip = max(math.dist(point, here), math.dist(theirs, here)) / view.speed
        return Rendezvous(here, step + self.params.wait + math.ceil(trip))

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


def overdue(meeting: Rendezvous | None, step: int) -> bool:
    """Whether ``meeting``'s agreed time has passed. Partners that meet after it have kept
    or missed it; neither may set out for it again. Before, the pair kept it when their
    contact lasted one step, so no new agreement was bound, and shuttled between the old
    point and the base (scenario 23, seeds 10, 13 and 18: stalled at 78.9 % explored)."""
    return meeting is not None and step > meeting.step


def improved_point(view: RobotView, frontier: tuple[float, float]) -> tuple[float, float] | None:
    """The original's improved rendezvous: of the skeleton junctions of the robot's known
    space within :data:`IMPROVED_REACH` cells of the frontier, the
    :data:`IMPROVED_CANDIDATES` nearest, scored by ``degree**2 * 1e4 / distance`` to the
    frontier (straight lines; the original: path length); None without a junction."""
    topology = plan_context(view).topology()
    junctions = topology.junctions
    if len(junctions) == 0:
        return None
    centres = junctions[:, ::-1] + 0.5  # (x, y)
    distance = np.hypot(*(centres - np.asarray(frontier)).T)
    near = np.flatnonzero(distance <= IMPROVED_REACH)
    if len(near) == 0:
        return None
    near = near[np.argsort(distance[near], kind="stable")[:IMPROVED_CANDIDATES]]
    skeleton = topology.skeleton
    degree = np.array([
        int(skeleton[max(r - 1, 0) : r + 2, max(c - 1, 0) : c + 2].sum()) - 1
        for r, c in junctions[near]
    ])  # fmt: skip
    score = degree.astype(float) ** 2 * 1e4 / np.maximum(distance[near], 1.0)
    best = near[int(np.argmax(score))]
    return float(centres[best, 0]), float(centres[best, 1])
