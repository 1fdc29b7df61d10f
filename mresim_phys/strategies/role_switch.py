"""``role_switch`` (phase 4, decide): role-based exploration with a dynamic hierarchy.

The original's role switch (J. de Hoog, S. Cameron, A. Visser, "Dynamic team hierarchies
in communication-limited multi-robot exploration", SSRR 2010; its
``SimulationFramework.switchRoles``) on top of :mod:`role_based`. A robot plays a
*position* of the team's hierarchy (at first its own: its role, parent and children); two
linked robots swap positions (roles, partners, meeting agreements) when that shortens the
longer of their trips: with ``a`` each one's path to its own goal and ``b`` its path to
the other's goal, when ``max(a1, a2) > max(b1, b2)``.

* **Agreed through the payload** (:class:`SwitchPayload`, only along the step's links):
  every ``switch_interval`` steps (10, after step 5) a robot that finds the rule true for
  a linked teammate ranking after it in the team's order offers the swap; the teammate
  takes it at its next decision (if it is free: not waiting at a meeting, not switched
  within ``min_between`` steps, no earlier-ranked offer in sight) and says so; the offerer
  swaps once it hears the acceptance, and drops the offer once it hears the teammate
  decided without it. A robot never takes an offer while it hears one ranking before it,
  and is in at most one swap a step, so robots that all hear each other swap one pair a
  step; two pairs that only hear each other through a third robot may swap in the same
  step (offers travel one hop; the original, central, swaps one pair a step in the team).
* **Second rule, two relays**: two relays linked while both carry news to the same
  parent: the one with the shorter trip back to its meeting point turns back and the
  other carries both maps on (each decides the same from the same records).
* **Under failures**: a relay that gives up its explorer (after ``wait + backup_wait``)
  or presumes it lost becomes an explorer (``Decision.role``) and explores on its own.

A robot's decision ``info`` shows the position it plays (``acting``) and its swaps.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import ClassVar

import numpy as np

from mresim_phys.knowledge.teammates import Payload, TeammateInfo
from mresim_phys.strategies.base import Decision, RobotView
from mresim_phys.strategies.base import plan_context as context_of
from mresim_phys.strategies.catalog import STRATEGIES
from mresim_phys.strategies.meetings import Rendezvous
from mresim_phys.strategies.params import RoleSwitchParams, StrategyParams
from mresim_phys.strategies.role_based import RoleBased

FIRST_CHECK = 5  # steps: no switch before (the original: after cycle 5)


@dataclass(frozen=True)
class SwitchPayload(Payload):
    """What a ``role_switch`` robot sends: the position it plays, its meeting agreement
    and state, and a swap it offers or took ((teammate, step of the offer))."""

    acting: str
    role: str
    parent: str | None
    children: tuple[str, ...]
    state: str
    rendezvous: Rendezvous | None = None
    offer: tuple[str, int] | None = None
    accept: tuple[str, int] | None = None
    proposal: Rendezvous | None = None  # an explorer's proposed next meeting (role_based)


def switch_payload(record: TeammateInfo | None) -> SwitchPayload | None:
    """The teammate's role switch payload, if it sent one."""
    payload = record.payload if record is not None else None
    return payload if isinstance(payload, SwitchPayload) else None


@STRATEGIES.register
class RoleSwitch(RoleBased):
    """Role-based exploration whose robots swap positions when it shortens their trips."""

    name = "role_switch"
    Params: ClassVar[type[StrategyParams]] = RoleSwitchParams
    params: RoleSwitchParams

    def __init__(self, params: RoleSwitchParams) -> None:
        super().__init__(params)
        self.acting = ""  # the hierarchy position it plays ('' until its first decision)
        self.position: tuple[str, str | None, tuple[str, ...]] = ("explorer", None, ())
        self.known: dict[str, tuple[int, str]] = {}  # position -> (step, player) from swaps
        self.pending: tuple[str, int] | None = None  # an offer it waits on
        self.offered_to: SwitchPayload | None = None  # the teammate's payload when offered
        self.offered_goal: tuple[float, float] | None = None  # and its goal then
        self.taken_goal: tuple[float, float] | None = None  # the goal it took in a swap
        self.accepted: tuple[str, int] | None = None
        self.last_switch = -(10**9)
        self.swaps = 0
        self.sent_back = 0
        self.free = False  # a relay without an explorer: explores on its own

    def replan_now(self, step: int, position: tuple[float, float], links: tuple[str, ...]) -> bool:
        """Role-based's moments, and the three steps of a switch check while linked."""
        due = super().replan_now(step, position, links)
        phase = step % self.params.switch_interval
        linked = any(name != "base" for name in links)
        return due or (linked and step > FIRST_CHECK and phase <= 2)

    def decide(self, view: RobotView) -> Decision:
        """Settle offers, play its position's rule, offer a swap at check steps."""
        if not self.acting:
            self.acting, self.position = view.name, (view.role, view.parent, view.children)
        self._settle(view)
        acting = self._acting_view(view)
        if acting.role == "relay" and self.state == "carry":
            self._second_rule(acting)
        was = self.state
        decision = super().decide(acting)
        if self.taken_goal is not None:
            decision = self._take_goal(acting, decision)
        if acting.role == "relay" and not self.free and self._lost_explorer(acting, was):
            self.free, self.partner, self.meeting = True, None, None
            self.state = "explore"
            decision = super().decide(self._acting_view(view))
        offer = self._offer(view, decision) if self.pending is None else None
        self.pending = offer or self.pending
        return self._send(view, decision, offer)

    def _take_goal(self, view: RobotView, decision: Decision) -> Decision:
        """An explorer heads for the goal it took in a swap until it gets there (or its
        state turns to the meeting), as the original swaps goals with roles."""
        goal = self.taken_goal
        if goal is None or self.state != "explore" or math.dist(view.position, goal) <= view.speed:
            self.taken_goal = None
            return decision
        return replace(self._go(view, goal, decision.payload), info=decision.info)

    # ---------------------------------------------------------------- positions

    def _player(self, view: RobotView, position: str) -> str:
        """The robot that plays ``position``: the newest of what swaps and records say."""
        if position in ("base", self.acting):
            return view.name if position == self.acting else position
        step, player = self.known.get(position, (-1, position))
        for record in view.teammates.values():
            claim = switch_payload(record)
            if claim is not None and claim.acting == position and record.step > step:
                step, player = record.step, record.name
        return player

    def _acting_view(self, view: RobotView) -> RobotView:
        role, parent, children = self.position
        if self.free:
            return replace(view, role="explorer", parent=None, children=())
        return replace(
            view,
            role=role,
            parent=None if parent is None else self._player(view, parent),
            children=tuple(self._player(view, child) for child in children),
        )

    def _lost_explorer(self, view: RobotView, was: str) -> bool:
        """A relay gave its explorer up (the wait ran out) or presumes it lost."""
        gave_up = was == "wait" and self.state == "explore" and self.meeting is None
        return gave_up or any(child in view.lost for child in view.children)

    # ---------------------------------------------------------------- the rule

    def _offer(self, view: RobotView, decision: Decision) -> tuple[str, int] | None:
        """At a check step: a swap with the first linked teammate for which the rule holds."""
        step = view.step
        if step <= FIRST_CHECK or step % self.params.switch_interval or not self._free_to(step):
            return None
        if decision.goal is None or self._earlier_offer(view, view.name):
            return None
        for name in sorted(view.links, key=view.tie_rank):
            record = view.teammates.get(name)
            theirs = switch_payload(record)
            if record is None or theirs is None or view.tie_rank(name) < view.tie_rank(view.name):
                continue
            free = theirs.state != "wait" and theirs.acting != self.acting
            if (
                free
                and record.goal is not None
                and self._rule(view, decision.goal, record.position, record.goal)
            ):
                self.offered_to, self.offered_goal = theirs, record.goal
                return (name, step)
        return None

    def _rule(
        self,
        view: RobotView,
        mine: tuple[float, float],
        there: tuple[float, float],
        theirs: tuple[float, float],
    ) -> bool:
        """The dynamic hierarchy rule, on the robot's own map: max(a1, a2) > max(b1, b2)."""
        context = context_of(view)
        cells = np.array([[math.floor(p[1]), math.floor(p[0])] for p in (mine, theirs)])
        own = context.field.cost_at(cells[:, 0], cells[:, 1])  # a1, b1
        other = context.field_from(there).cost_at(cells[:, 0], cells[:, 1])  # b2, a2
        a, b = max(own[0], other[1]), max(own[1], other[0])
        return bool(np.isfinite(b) and a > b)

    def _free_to(self, step: int) -> bool:
        return (
            not self.free
            and self.state != "wait"
            and step - self.last_switch >= (self.params.min_between)
        )

    def _earlier_offer(self, view: RobotView, than: str) -> bool:
        """Whether a linked teammate ranking before ``than`` offers a swap now."""
        rank = view.tie_rank(than)
        for name in view.links:
            theirs = switch_payload(view.teammates.get(name))
            offer = theirs.offer if theirs is not None else None
            if offer is not None and offer[1] >= view.step - 2 and view.tie_rank(name) < rank:
                return True
        return False

    # ---------------------------------------------------------------- the handshake

    def _settle(self, view: RobotView) -> None:
        """Take an offer made to it; finish or drop its own offer."""
        if self.pending is not None:
            name, step = self.pending
            record = view.teammates.get(name)
            theirs = switch_payload(record)
            if record is not None and theirs is not None and record.step > step:
                if theirs.accept == (view.name, step) and self.offered_to is not None:
                    # its position and goal before it swapped
                    self._swap(view, name, self.offered_to, self.offered_goal)
                self.pending = self.offered_to = None
            elif view.step > step + 2 * self.params.switch_interval:
                self.pending = self.offered_to = None  # never heard back: out of reach
        for name in sorted(view.links, key=view.tie_rank):
            theirs = switch_payload(view.teammates.get(name))
            offer = theirs.offer if theirs is not None else None
            if theirs is None or offer is None or offer[0] != view.name:
                continue
            takes = offer[1] >= view.step - 2 and self._free_to(view.step)
            if takes and self.pending is None and not self._earlier_offer(view, name):
                self._swap(view, name, theirs, view.teammates[name].goal)
                self.accepted = (name, offer[1])
            break

    def _swap(
        self,
        view: RobotView,
        other: str,
        theirs: SwitchPayload,
        goal: tuple[float, float] | None,
    ) -> None:
        """Take the teammate's position (role, partners, meeting), state and goal; it takes
        ours."""
        old = self.acting
        self.known[old] = (view.step, other)
        self.known[theirs.acting] = (view.step, view.name)
        self.acting = theirs.acting
        self.position = (theirs.role, theirs.parent, theirs.children)
        self.meeting, self.proposal = theirs.rendezvous or self.meeting, None
        self.state = theirs.state  # its state and goal go with the position, as the original's
        self.last_switch, self.swaps = view.step, self.swaps + 1
        self.planner.forget()
        self.taken_goal = goal if theirs.role != "relay" else None

    def _second_rule(self, view: RobotView) -> None:
        """Two relays carrying to the same parent: the one nearer its meeting turns back."""
        meeting = self.meeting
        if meeting is None:
            return
        back = math.dist(view.position, meeting.relay_at)
        for name in view.links:
            record = view.teammates.get(name)
            theirs = switch_payload(record)
            if record is None or theirs is None or theirs.role != "relay":
                continue
            if (
                theirs.state != "carry"
                or theirs.parent != self.position[1]
                or not theirs.rendezvous
            ):
                continue
            their_back = math.dist(record.position, theirs.rendezvous.relay_at)
            nearer = (back, view.tie_rank(view.name)) < (their_back, view.tie_rank(name))
            if nearer:
                self.state, self.sent_back = "to_rv", self.sent_back + 1
                return

    def agreement_of(self, record: TeammateInfo) -> Rendezvous | None:
        """A role switch teammate's agreement travels inside its :class:`SwitchPayload`."""
        theirs = switch_payload(record)
        return theirs.proposal if theirs is not None else super().agreement_of(record)

    def _send(self, view: RobotView, decision: Decision, offer: tuple[str, int] | None) -> Decision:
        role, parent, children = ("explorer", None, ()) if self.free else self.position
        payload = SwitchPayload(
            self.acting, role, parent, children, self.state, self.meeting, offer, self.accepted,
            self.proposal,
        )  # fmt: skip
        info = {**decision.info, "acting": self.acting, "swaps": self.swaps}
        info["parent"] = self._acting_view(view).parent  # the hierarchy layer draws it
        new_role = role if role != view.role else None
        return replace(decision, payload=payload, role=new_role, info=info)
