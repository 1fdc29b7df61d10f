"""Run trackers (phase 7, metrics): what the run remembers of its steps, read from columns.

Each tracker is fed every step's facts (``metrics.StepRecord``) and reads them through the
metric columns (``columns.value_of``), as ``metrics.csv`` does: :class:`Milestones` (the
first step each fraction crossed 0.5 / 0.9 / 0.95), :class:`StallWatch` (the stall rule,
``stop.stalled_for``), :class:`Curves` (the explored and known-at-base curves, for their
areas) and :class:`CommTotals` (communication over the run, for ``summary.json``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from mresim_phys.columns import value_of
from mresim_phys.knowledge.coverage import Coverage
from mresim_phys.knowledge.health import Progress
from mresim_phys.metrics import THRESHOLDS, StepRecord
from mresim_phys.scenario.run_specs import BudgetSpec

MILESTONE_COLUMNS = ("explored", "known_at_base", "explored_connected", "known_at_base_connected")


def number(name: str, record: StepRecord) -> float | None:
    """Column ``name``'s value at ``record``'s step as a number (None: not measured)."""
    value = value_of(name, record)
    if value is None:
        return None
    if not isinstance(value, (int, float)):
        raise TypeError(f"column {name!r} is not a number per step")
    return value


def count(name: str, record: StepRecord) -> int:
    """Column ``name``'s value at ``record``'s step as a whole number (None counts 0)."""
    return int(number(name, record) or 0)


def fraction(name: str, record: StepRecord) -> float:
    """Column ``name``'s value at ``record``'s step as a float (None counts 0)."""
    value = number(name, record)
    return 0.0 if value is None else value


def no_milestones(levels: tuple[float, ...] = THRESHOLDS) -> dict[str, int | None]:
    """Every threshold, none reached yet."""
    return dict.fromkeys(map(str, levels))


def budget_level(budget: BudgetSpec | None) -> list[float]:
    """The level a scenario's ``metrics.budget`` asks for (tracked as a milestone), or none."""
    if budget is None:
        return []
    level = budget.explored if budget.explored is not None else budget.known_at_base
    return [] if level is None else [level]


def thresholds_with(levels: list[float] | tuple[float, ...]) -> tuple[float, ...]:
    """The milestones' thresholds and a scenario's ``metrics.levels``, in order."""
    return tuple(sorted(set(THRESHOLDS) | set(levels)))


@dataclass
class Milestones:
    """First step at which ``explored`` / ``known_at_base`` (and their ``_connected``
    versions) reached each threshold (0.5, 0.9, 0.95 and a scenario's ``levels``)."""

    levels: tuple[float, ...] = THRESHOLDS
    explored: dict[str, int | None] = field(default_factory=no_milestones)
    known_at_base: dict[str, int | None] = field(default_factory=no_milestones)
    explored_connected: dict[str, int | None] = field(default_factory=no_milestones)
    known_at_base_connected: dict[str, int | None] = field(default_factory=no_milestones)

    def __post_init__(self) -> None:
        if self.levels != THRESHOLDS:
            for name in MILESTONE_COLUMNS:
                setattr(self, name, no_milestones(self.levels))

    def update(self, record: StepRecord) -> None:
        """Note thresholds first crossed by ``record``."""
        for name in MILESTONE_COLUMNS:
            value = number(name, record)
            table = getattr(self, name)
            for threshold in self.levels:
                key = str(threshold)
                if table[key] is None and value is not None and value >= threshold:
                    table[key] = record.step


def explorable_summary(
    coverage: Coverage, last: StepRecord, milestones: Milestones
) -> dict[str, object]:
    """summary.json's fields about what the fractions count: the explorable cells and the
    connected ones at the last step, and the ``_connected`` fractions' final values and
    milestones."""
    return {
        "explorable_cells": coverage.total,
        "connected_cells": coverage.total_connected if coverage.connected is not None else None,
        "final_explored_connected": number("explored_connected", last),
        "final_known_at_base_connected": number("known_at_base_connected", last),
        "steps_to_explored_connected": dict(milestones.explored_connected),
        "steps_to_known_at_base_connected": dict(milestones.known_at_base_connected),
    }


@dataclass
class StallWatch:
    """When the run last made progress: a gain of ``gain`` in explored or known at base,
    or a robot done for the first time (it sets out to bring its map home).

    The run is stalled once ``window`` steps have passed since the last step at which
    either fraction rose by at least ``gain`` above its value at the progress before, or
    a robot was first ``done`` (``stop.stalled_for`` / ``stop.stalled_gain``). Slow, steady
    gains add up: 0.01 % a step for ten steps is a gain of 0.1 %. A robot done counts once,
    so the rule ends a run at most one window per robot later than the gains alone would.
    """

    window: int | None
    gain: float
    progress: Progress = field(init=False)  # the measure run health shares
    set_out: set[str] = field(init=False, default_factory=set)  # robots done at least once
    last_set_out: int = field(init=False, default=0)  # the step a robot was first done

    def __post_init__(self) -> None:
        self.progress = Progress(self.gain)

    @property
    def last_progress(self) -> int:
        """The last step at which the run made progress."""
        return max(self.progress.step, self.last_set_out)

    def update(self, record: StepRecord) -> None:
        """Note progress made by ``record``."""
        explored, known = fraction("explored", record), fraction("known_at_base", record)
        self.progress.update(record.step, explored, known)
        done = {robot.name for robot in record.robots if robot.state == "done"}
        if done - self.set_out:
            self.set_out |= done
            self.last_set_out = record.step

    def stalled(self, step: int) -> bool:
        """No progress in the last ``window`` steps."""
        return self.window is not None and step - self.last_progress >= self.window


@dataclass
class CommTotals:
    """Communication over the whole run, for ``summary.json``."""

    comm_bytes: int = 0
    control_bytes: int = 0
    link_steps: int = 0  # sum over steps of the linked pairs
    latency_max: float = 0.0
    latency_sum: float = 0.0
    steps: int = 0
    # the radio columns the run writes (``comms/radio_feature.py``), totalled: their sums,
    # the backlog's peak and the mean share connected to the base
    radio: tuple[str, ...] = ()
    radio_sums: dict[str, float] = field(default_factory=dict)

    def update(self, record: StepRecord) -> None:
        """Add one step."""
        self.comm_bytes += count("comm_bytes", record)
        self.control_bytes += count("control_bytes", record)
        self.link_steps += count("links", record)
        self.latency_max = max(self.latency_max, fraction("latency_max", record))
        self.latency_sum += fraction("latency_mean", record)
        self.steps += 1
        for name in self.radio:
            self.add_radio(name, value_of(name, record))

    def add_radio(self, name: str, value: object) -> None:
        """Add one step's value of radio column ``name`` (a per-robot column: its peak)."""
        sums = self.radio_sums
        if isinstance(value, (list, tuple)):
            peak = max((v for v in value if isinstance(v, (int, float))), default=0)
            sums[f"{name}_max"] = max(sums.get(f"{name}_max", 0), peak)
        elif isinstance(value, (int, float)):
            sums[name] = sums.get(name, 0) + value

    def summary(self) -> dict[str, float | int]:
        """The totals as JSON-ready numbers (and the radio's, when the run has them:
        bytes summed over the run, ``backlog_max``, ``connected_to_base_mean``)."""
        totals: dict[str, float | int] = {
            "comm_bytes": self.comm_bytes,
            "control_bytes": self.control_bytes,
            "mean_links": self.link_steps / self.steps if self.steps else 0.0,
            "latency_max": self.latency_max,
            "latency_mean": self.latency_sum / self.steps if self.steps else 0.0,
        }
        radio = dict(self.radio_sums)
        if "connected_to_base" in radio:
            radio["connected_to_base_mean"] = radio.pop("connected_to_base") / max(self.steps, 1)
        return totals | {k: int(v) if k.startswith(("bytes", "backlog")) else v
                         for k, v in sorted(radio.items())}  # fmt: skip


@dataclass
class Curves:
    """The explored and known-at-base curves of the run, step by step (for their areas)."""

    explored: list[float] = field(default_factory=list)
    known_at_base: list[float] = field(default_factory=list)

    def update(self, record: StepRecord) -> None:
        """Add one step (steps come in order from 0)."""
        self.explored.append(fraction("explored", record))
        self.known_at_base.append(fraction("known_at_base", record))
