"""Appointments (phase 4, decide): the meetings a strategy has agreed, as it tells the run.

A strategy that plans meetings (``role_based``, ``role_switch``, ``sector_rendezvous``,
``leader_follower``, ``utility_return``) says which meetings bind its robot now through
one explicit call, :meth:`PlansMeetings.appointments`: each an :class:`Appointment`
(the partner, a robot's name or ``"base"``; the robot's own point, in its believed
frame; the agreed step; the last step it keeps the meeting). The run's rendezvous
accounting (``meetings/watch.py``) asks every robot after each step and judges the
meetings from the truth; it never reads a strategy's internals, and a strategy never
sees the judgement. Rules: ``docs/rendezvous.md``.

Typical use: ``appointments_of(robot.strategy)``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

BASE = "base"  # the partner of a return to the base (utility_return)


@dataclass(frozen=True)
class Appointment:
    """A meeting that binds a robot: with ``partner`` at ``point`` (the robot's own point,
    believed frame) at step ``step``; a link from step ``opens`` (None: ``step``) to step
    ``closes`` (inclusive) keeps it."""

    partner: str
    point: tuple[float, float]
    step: int
    closes: int
    opens: int | None = None

    @property
    def window(self) -> tuple[int, int]:
        """(first, last) step at which a link keeps the meeting."""
        return (self.step if self.opens is None else self.opens), self.closes


@runtime_checkable
class PlansMeetings(Protocol):
    """A strategy whose robots agree meetings and report them."""

    def appointments(self) -> tuple[Appointment, ...]:
        """The meetings that bind its robot now (as of its last decision)."""
        ...


def appointments_of(strategy: object) -> tuple[Appointment, ...]:
    """What ``strategy`` reports (nothing from a strategy that plans no meetings)."""
    return strategy.appointments() if isinstance(strategy, PlansMeetings) else ()


def plans_meetings(strategy_class: type) -> bool:
    """Whether instances of ``strategy_class`` report appointments."""
    return callable(getattr(strategy_class, "appointments", None))
