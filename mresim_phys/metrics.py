"""Metrics (phase 7): what one step achieved, in numbers.

``explored`` is the fraction of truth-free cells reachable from the robots'
starts that the team (robots and base together) has marked free;
``known_at_base`` the same for the base station's own grid. Both are in [0, 1]
and never decrease. A :class:`StepRecord` is one row of ``metrics.csv``;
:class:`Milestones` remembers the first step each fraction crossed 0.5/0.9/0.95.
"""

from __future__ import annotations

from dataclasses import dataclass, field

THRESHOLDS = (0.5, 0.9, 0.95)


@dataclass(frozen=True)
class RobotRecord:
    """One robot in one step."""

    name: str
    distance: float
    state: str


@dataclass(frozen=True)
class StepRecord:
    """Everything measured at the end of one step."""

    step: int
    explored: float
    known_at_base: float
    distance: float
    alive: int
    links: int
    robots: tuple[RobotRecord, ...]

    def csv_row(self) -> list[str]:
        """Values in :func:`csv_header` order, floats as exact round-trip text."""
        row = [
            str(self.step),
            repr(self.explored),
            repr(self.known_at_base),
            repr(self.distance),
            str(self.alive),
            str(self.links),
        ]
        row += [repr(r.distance) for r in self.robots]
        row += [r.state for r in self.robots]
        return row


def csv_header(robot_names: list[str]) -> list[str]:
    """Column names of ``metrics.csv``."""
    return (
        ["step", "explored", "known_at_base", "distance", "alive", "links"]
        + [f"distance_{n}" for n in robot_names]
        + [f"state_{n}" for n in robot_names]
    )


@dataclass
class Milestones:
    """First step at which ``explored`` / ``known_at_base`` reached each threshold."""

    explored: dict[str, int | None] = field(
        default_factory=lambda: dict.fromkeys(map(str, THRESHOLDS))
    )
    known_at_base: dict[str, int | None] = field(
        default_factory=lambda: dict.fromkeys(map(str, THRESHOLDS))
    )

    def update(self, record: StepRecord) -> None:
        """Note thresholds first crossed by ``record``."""
        for name, value in (("explored", record.explored), ("known_at_base", record.known_at_base)):
            table = getattr(self, name)
            for threshold in THRESHOLDS:
                key = str(threshold)
                if table[key] is None and value >= threshold:
                    table[key] = record.step
