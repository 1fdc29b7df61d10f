"""Robustness metrics (phase 7, measure): what each robot failure cost the team's knowledge.

Nothing here is told that a robot failed: at the end of every step :class:`FailureWatch`
compares each robot's fault state (failed or not, its broken parts) with the previous
step's, so a failure from any source (a scheduled ``fail`` event, a collapse that buries a
robot, a random fault model) is seen the same way, live and in a replay (which reads the
same state from the run log's agent lines).

A failure *silences* a robot when it stops speaking: the whole robot or its radio fails
(a robot whose drive or sensor failed still talks, so its knowledge still reaches the
team). At a silencing failure of robot R at step t, over the reachable free cells of
step t (the cells the ``explored`` metric counts):

* ``knowledge_unreported`` = cells R's map holds FREE that the base's map does not;
* ``knowledge_lost`` = those of them that no robot still speaking holds FREE either
  (the knowledge that died with R, for now);

each also as a fraction of the reachable free cells. ``recovery_steps`` is the number of
steps after t until every lost cell has been held FREE again, at some step, by the base
or a robot then speaking (``recovery_steps_base``: by the base); ``None`` (``never`` in
summary.json) if the run ends first. A lost cell that stops being reachable (a collapse)
is no longer waited for. A failure that does not silence the robot is listed with its
parts and no knowledge figures. Formulas: docs/robustness.md.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from mresim_phys.broken_parts import broken_of
from mresim_phys.types import FREE, BeliefGrid, BoolGrid, IntArray

NO_CELLS = np.zeros(0, np.int64)


@dataclass(frozen=True)
class FaultState:
    """What the watch reads of one robot at the end of a step."""

    name: str
    belief: BeliefGrid
    failed: bool
    broken: frozenset[str]

    @property
    def speaking(self) -> bool:
        """Its knowledge still reaches teammates: not failed, radio working."""
        return speaking(self.failed, self.broken)


def speaking(failed: bool, broken: frozenset[str]) -> bool:
    """Whether a robot in this fault state still talks (one rule, live and replayed)."""
    return not failed and "radio" not in broken


@dataclass
class FailureRecord:
    """One robot's failure at one step and, if it silenced the robot, its knowledge cost."""

    step: int
    robot: str
    parts: tuple[str, ...]
    silenced: bool
    total: int  # reachable free cells at the failure
    lost: IntArray = field(default_factory=lambda: NO_CELLS)  # flat indices
    unreported: int = 0
    pending_team: IntArray = field(default_factory=lambda: NO_CELLS)
    pending_base: IntArray = field(default_factory=lambda: NO_CELLS)
    recovered_team: int | None = None  # step
    recovered_base: int | None = None

    @property
    def knowledge_lost(self) -> int:
        """Cells only the failed robot knew."""
        return len(self.lost)

    def summary(self) -> dict[str, Any]:
        """The failure as a JSON-ready entry of summary.json's ``failures``."""
        entry: dict[str, Any] = {"step": self.step, "robot": self.robot, "parts": list(self.parts)}
        if not self.silenced:
            return {**entry, "silenced": False}
        share = 1.0 / self.total if self.total else 0.0
        return {
            **entry,
            "silenced": True,
            "knowledge_lost": self.knowledge_lost,
            "knowledge_lost_fraction": self.knowledge_lost * share,
            "knowledge_unreported": self.unreported,
            "knowledge_unreported_fraction": self.unreported * share,
            "recovery_steps": steps_since(self.recovered_team, self.step),
            "recovery_steps_base": steps_since(self.recovered_base, self.step),
        }


def steps_since(step: int | None, start: int) -> int | str:
    """``step - start``, or ``"never"``."""
    return "never" if step is None else step - start


def free_at(belief: BeliefGrid, cells: IntArray) -> BoolGrid:
    """Which of the flat ``cells`` ``belief`` holds FREE."""
    held: BoolGrid = belief.reshape(-1)[cells] == FREE
    return held


def unknown_to(beliefs: Sequence[BeliefGrid], cells: IntArray) -> IntArray:
    """The cells of ``cells`` that none of ``beliefs`` holds FREE."""
    for belief in beliefs:
        if len(cells) == 0:
            break
        cells = cells[~free_at(belief, cells)]
    return cells


class FailureWatch:
    """Notices failures from the robots' fault states and follows the knowledge they cost."""

    def __init__(self, names: Sequence[str]) -> None:
        self.before: dict[str, tuple[bool, frozenset[str]]] = {
            n: (False, frozenset()) for n in names
        }
        self.failures: list[FailureRecord] = []
        self.lost_mask: BoolGrid | None = None  # every cell lost at some failure (for display)
        self.knowledge_lost = 0  # cells lost, summed over failures
        self.lost_unrecovered = 0  # lost cells the team has not known again yet, summed

    def update(
        self,
        step: int,
        robots: Sequence[FaultState],
        base: BeliefGrid,
        reachable: BoolGrid,
        total: int,
    ) -> list[FailureRecord]:
        """Note this step's failures and recoveries; return the failures new this step."""
        new = []
        for robot in robots:
            failure = self.notice(step, robot)
            if failure is not None:
                new.append(failure)
        talking = [base, *(r.belief for r in robots if r.speaking)]
        for failure in new:
            if failure.silenced:
                self.cost(failure, robots, talking, reachable, total)
        self.failures += new
        self.follow(step, talking, base, reachable)
        return new

    def notice(self, step: int, robot: FaultState) -> FailureRecord | None:
        """A failure if ``robot`` lost something since the last step."""
        was_failed, was_broken = self.before[robot.name]
        self.before[robot.name] = (robot.failed, robot.broken)
        parts = sorted(robot.broken - was_broken)
        if robot.failed and not was_failed:
            parts = ["robot", *parts]
        if not parts:
            return None
        silenced = speaking(was_failed, was_broken) and not robot.speaking
        return FailureRecord(step, robot.name, tuple(parts), silenced, total=0)

    def cost(
        self,
        failure: FailureRecord,
        robots: Sequence[FaultState],
        talking: list[BeliefGrid],
        reachable: BoolGrid,
        total: int,
    ) -> None:
        """Fill in what a silencing failure lost (one pass over the failed robot's map)."""
        belief = next(r.belief for r in robots if r.name == failure.robot)
        known = np.flatnonzero((belief == FREE) & reachable)
        unreported = unknown_to(talking[:1], known)
        lost = unknown_to(talking[1:], unreported)
        failure.total, failure.unreported, failure.lost = total, len(unreported), lost
        failure.pending_team, failure.pending_base = lost, lost
        self.knowledge_lost += len(lost)
        if len(lost):
            if self.lost_mask is None:
                self.lost_mask = np.zeros(reachable.shape, dtype=bool)
            self.lost_mask.reshape(-1)[lost] = True

    def follow(
        self, step: int, talking: list[BeliefGrid], base: BeliefGrid, reachable: BoolGrid
    ) -> None:
        """Drop the lost cells known again (or no longer reachable); note full recoveries."""
        self.lost_unrecovered = 0
        for f in self.failures:
            if f.silenced and f.recovered_team is None:
                f.pending_team = unknown_to(talking, still(reachable, f.pending_team))
                if len(f.pending_team) == 0:
                    f.recovered_team = step
                self.lost_unrecovered += len(f.pending_team)
            if f.silenced and f.recovered_base is None:
                f.pending_base = unknown_to([base], still(reachable, f.pending_base))
                if len(f.pending_base) == 0:
                    f.recovered_base = step

    def columns(self) -> tuple[int, int, int]:
        """The metrics.csv columns: failures so far, cells lost (summed over failures),
        lost cells the team has not known again yet (summed over failures)."""
        return len(self.failures), self.knowledge_lost, self.lost_unrecovered

    def notes(self) -> tuple[tuple[int, str], ...]:
        """(step, robot and failed parts other than 'robot') of every failure so far."""
        return tuple(
            (f.step, " ".join([f.robot, *(p for p in f.parts if p != "robot")]))
            for f in self.failures
        )

    def lost_view(self) -> BoolGrid | None:
        """Every cell lost at some failure so far, read-only (None: none yet)."""
        if self.lost_mask is None:
            return None
        view: BoolGrid = self.lost_mask.view()
        view.flags.writeable = False
        return view

    def summary(self) -> list[dict[str, Any]]:
        """summary.json's ``failures``: one entry per failure, in order."""
        return [f.summary() for f in self.failures]


def still(reachable: BoolGrid, cells: IntArray) -> IntArray:
    """The cells of ``cells`` still reachable."""
    kept: IntArray = cells[reachable.reshape(-1)[cells]]
    return kept


def robot_states(robots: Sequence[Any]) -> list[FaultState]:
    """Fault states of live robots (``agents.Robot``: ``broken``, over its ``parts`` state)."""
    return [FaultState(r.name, r.belief, r.state == "failed", frozenset(r.broken)) for r in robots]


def logged_states(robots: Sequence[Any]) -> list[FaultState]:
    """Fault states of logged robots (``AgentSnapshot``: the ``parts`` feature's value)."""
    return [FaultState(r.name, r.belief, r.state == "failed", broken_of(r)) for r in robots]
