"""Viewer (output edge), timeline: the chart series and the event marks of a run.

For every step: the explored and known-at-base fractions (the page's chart) and the
step's events (failures, doors, debris, ... : ``Snapshot.events``), which the page draws
as marks on the scrubber; a robot whose state turns ``failed`` without an event of its
own (a random fault) is marked too, and so is a robot that declares itself done or turns
active again after that, with the reason the run gave (``B done (no reachable frontier)``: the
run-health record's state changes, ``knowledge/health.py``). Filled step by step, live or
from a log's index.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from mresim_phys.metrics import StepRecord
from mresim_phys.tracking import fraction

CHART = ("explored", "known_at_base")  # the metric columns the page's chart draws


@dataclass
class Timeline:
    """Per-step series and events, in step order."""

    steps: list[int] = field(default_factory=list)
    explored: list[float] = field(default_factory=list)
    known_at_base: list[float] = field(default_factory=list)
    events: list[tuple[int, str]] = field(default_factory=list)  # (logged step n, text)
    _states: list[str] = field(default_factory=list)

    def add(
        self,
        record: StepRecord,
        events: Sequence[str],
        states: Sequence[str],
        reasons: Sequence[str | None] = (),
    ) -> None:
        """Add the next step: its record, its events, the robots' states and the reasons
        of the state changes of this step (None where a robot's state did not change)."""
        n = len(self.steps)
        self.steps.append(record.step)
        self.explored.append(fraction(CHART[0], record))
        self.known_at_base.append(fraction(CHART[1], record))
        self.events += [(n, text) for text in events]
        if self._states:
            told = " ".join(events)
            for robot, (was, now) in enumerate(zip(self._states, states, strict=True)):
                name = record.robots[robot].name if robot < len(record.robots) else str(robot)
                if now == "failed" and was != "failed" and name not in told:
                    self.events.append((n, f"{name} failed"))
                reason = reasons[robot] if robot < len(reasons) else None
                if "done" in (was, now) and "failed" not in (was, now) and was != now:
                    self.events.append((n, f"{name} {now} ({reason or 'no reason logged'})"))
        self._states = list(states)

    def __len__(self) -> int:
        return len(self.steps)

    def to_json(self, start: int = 0) -> dict[str, Any]:
        """Entries from logged step ``start`` on (fractions rounded to 5 digits)."""
        return {
            "start": start,
            "steps": self.steps[start:],
            "explored": [round(v, 5) for v in self.explored[start:]],
            "known_at_base": [round(v, 5) for v in self.known_at_base[start:]],
            "events": [[n, text] for n, text in self.events if n >= start],
        }
