"""Rendezvous accounting (phase 7, metrics), the judge: each meeting kept, missed or superseded.

After every step's communication phase the simulation hands :class:`MeetingWatch` the
step's main-channel links (index 0 the base) and its robots. The watch asks each robot's
strategy for the meetings that bind it (``strategies/appointments.py``) and judges them
from the truth:

* a meeting is the pair (the two parties, agent order) and its agreed step; each party
  that reports it gives its own point (believed frame) and its window (by default from
  the agreed step to the end of its wait; a return to the base or a step back opens when
  the robot sets out); the meeting's window runs from the earliest opening to the latest
  close;
* it is **planned** at the first step its parties are not linked while one of them holds
  it (an agreement replaced while the pair is still together is a draft, not counted);
* it is **kept** at the first step after it was planned at which its parties are linked
  on the main channel, within its window or, before the window, while a party it binds
  stands at its point (it came early and found the other there);
* it is **superseded** when no party holds it any more before its window closed (a new
  agreement replaced it, as when the pair met by chance elsewhere before the window, or
  the strategy withdrew it);
* otherwise it is **missed** when its window closes, for the first of these reasons:
  ``partner_failed`` (a party was failed at some step since it was planned), ``link_failed``
  (at some step every party it binds was at its point, and they were not linked: drift
  put them elsewhere, or the radio failed), ``late`` (never all at their points at once).

A party is at its point when its **believed** position is within its speed plus
:data:`AT_POINT` cells of it (where it thinks it stands, as its strategy does); the base,
and a partner the meeting does not bind, is always there. Waiting time: the steps a
party spent at its point after the meeting was planned and before it was kept or its
window closed.

Typical use: ``board = watch.update(step, links, robots)`` once per step.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np

from mresim_phys.meeting_board import MARK_STEPS, REASONS, Meeting, MeetingBoard, Outcome, Tally
from mresim_phys.strategies.appointments import (
    Appointment,
    PlansMeetings,
    appointments_of,
    plans_meetings,
)
from mresim_phys.strategies.catalog import STRATEGIES

if TYPE_CHECKING:
    from mresim_phys.agents import Robot

AT_POINT = 2.0  # cells beyond a robot's speed: it stands at its meeting point
Key = tuple[str, str, int]  # the parties (agent order) and the agreed step


@dataclass
class Open:
    """A meeting being followed: who holds it, since when, what was seen."""

    key: Key
    points: dict[str, tuple[float, float]] = field(default_factory=dict)
    closes: dict[str, int] = field(default_factory=dict)
    opens: dict[str, int] = field(default_factory=dict)
    planned: int | None = None
    waited: dict[str, int] = field(default_factory=dict)
    failed: bool = False  # a party was failed at some step since it was planned
    unlinked_there: bool = False  # every bound party at its point, and no link

    def meeting(self) -> Meeting:
        """The meeting as the board shows it."""
        a, b, step = self.key
        points = (self.points.get(a), self.points.get(b))
        return Meeting((a, b), points, step, max(self.closes.values()), self.planned or 0)

    def outcome(self, step: int, result: str, reason: str | None = None) -> Outcome:
        """Its judgement at ``step``."""
        a, b, _ = self.key
        waited = (self.waited.get(a), self.waited.get(b))
        return Outcome(self.meeting(), step, result, reason, waited)


@dataclass
class MeetingWatch:
    """The judge (module docstring) over a team whose agents are ``names`` (base first)."""

    names: tuple[str, ...]
    open: dict[Key, Open] = field(default_factory=dict)
    closed: set[Key] = field(default_factory=set)
    outcomes: list[Outcome] = field(default_factory=list)  # every judgement, in order
    tally: Tally = field(default_factory=Tally)

    def update(self, step: int, links: np.ndarray, robots: Sequence[Robot]) -> MeetingBoard:
        """Judge the meetings after ``step`` (``links``: the main channel, base first)."""
        index = {name: i for i, name in enumerate(self.names)}
        by_name = {r.name: r for r in robots}
        held = self._held(robots, index)
        for key, mine in held.items():
            if key not in self.closed:
                meeting = self.open.setdefault(key, Open(key))
                for holder, appointment in mine.items():
                    meeting.points[holder] = appointment.point
                    meeting.opens[holder], meeting.closes[holder] = appointment.window
        for key, meeting in list(self.open.items()):
            linked = bool(links[index[key[0]], index[key[1]]])
            outcome = self._judge(meeting, step, held.get(key, {}), linked, by_name)
            if outcome is not None or (meeting.planned is None and key not in held):
                del self.open[key]
            if outcome is not None:
                self.closed.add(key)
                self.outcomes.append(outcome)
                self._count(outcome)
        return self.board(step)

    def _held(
        self, robots: Sequence[Robot], index: dict[str, int]
    ) -> dict[Key, dict[str, Appointment]]:
        """Every meeting some robot reports now, and who reports it."""
        held: dict[Key, dict[str, Appointment]] = {}
        for robot in robots:
            for appointment in appointments_of(robot.strategy):
                if appointment.partner not in index or appointment.partner == robot.name:
                    continue
                a, b = sorted((robot.name, appointment.partner), key=index.__getitem__)
                held.setdefault((a, b, appointment.step), {})[robot.name] = appointment
        return held

    def _judge(
        self, meeting: Open, step: int, holders: dict[str, Appointment], linked: bool,
        robots: dict[str, Robot],
    ) -> Outcome | None:  # fmt: skip
        """The meeting's judgement at ``step``, if it has one now."""
        if meeting.planned is None:
            if linked or not holders:
                return None  # a draft: the pair is still together, or dropped it
            meeting.planned = step
            self.tally = replace(self.tally, planned=self.tally.planned + 1)
        there = self._there(meeting, robots)
        if linked and (step >= min(meeting.opens.values()) or any(there.values())):
            return meeting.outcome(step, "kept")
        closes = max(meeting.closes.values())
        if not holders and step < closes:
            return meeting.outcome(step, "superseded")
        if linked:
            return None  # together before the window, away from the point: a chance encounter
        self._observe(meeting, robots, there)
        if step < closes:
            return None
        reason = "partner_failed" if meeting.failed else None
        reason = reason or ("link_failed" if meeting.unlinked_there else "late")
        return meeting.outcome(step, "missed", reason)

    def _there(self, meeting: Open, robots: dict[str, Robot]) -> dict[str, bool]:
        """Whether each robot the meeting binds stands at its point (alive, believed
        position within its speed plus :data:`AT_POINT` cells)."""
        out = {}
        for party, point in meeting.points.items():
            robot = robots.get(party)
            if robot is not None:
                reach = robot.body.speed + AT_POINT
                out[party] = robot.alive and math.dist(robot.believed_position, point) <= reach
        return out

    def _observe(self, meeting: Open, robots: dict[str, Robot], there: dict[str, bool]) -> None:
        """Failures, waiting and a missing link at the points, on a step the pair is not
        linked."""
        for party in meeting.key[:2]:
            robot = robots.get(party)
            meeting.failed |= robot is not None and not robot.alive
            if party in there:
                meeting.waited[party] = meeting.waited.get(party, 0) + int(there[party])
        if all(there.values()):
            meeting.unlinked_there = True

    def _count(self, outcome: Outcome) -> None:
        """Add a judgement to the tally."""
        t = self.tally
        if outcome.result == "kept":
            self.tally = replace(t, kept=t.kept + 1)
        elif outcome.result == "superseded":
            self.tally = replace(t, superseded=t.superseded + 1)
        else:
            missed = list(t.missed)
            missed[REASONS.index(outcome.reason or "late")] += 1
            self.tally = replace(t, missed=(missed[0], missed[1], missed[2]))

    def board(self, step: int) -> MeetingBoard:
        """What the step shows: the tally, the meetings pending, the recent judgements."""
        pending = tuple(m.meeting() for m in self.open.values() if m.planned is not None)
        recent = []
        for outcome in reversed(self.outcomes):
            if outcome.judged <= step - MARK_STEPS:
                break
            if outcome.result != "superseded":
                recent.append(outcome)
        return MeetingBoard(self.tally, pending, tuple(reversed(recent)))


def meeting_watch(names: Sequence[str], robots: Sequence[Robot]) -> MeetingWatch | None:
    """A watch for the team (agent ``names``, base first) if a robot's strategy plans
    meetings; None otherwise (the run has no meeting columns)."""
    if not any(isinstance(r.strategy, PlansMeetings) for r in robots):
        return None
    return MeetingWatch(tuple(names))


def strategies_plan_meetings(names: Iterable[str]) -> bool:
    """Whether a strategy of these registry names plans meetings (the run then has the
    meeting columns and summary.json's ``meetings``)."""
    return any(plans_meetings(STRATEGIES.get(name)) for name in set(names))
