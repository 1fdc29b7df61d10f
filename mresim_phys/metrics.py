"""Metrics (phase 7): what one step achieved, in numbers.

``explored`` is the fraction of the explorable cells (``world.explorable``: free cells
some robot can see from where its body can go) that the team (robots and base
together) has marked free; ``known_at_base`` the same for the base station's own grid.
Both are in [0, 1] and never decrease. ``explored_connected`` and
``known_at_base_connected`` are the same over the definition before the explorable area
(truth-free cells 4-connected to the robots' starts), for comparisons with earlier runs.
``links`` counts linked agent pairs (the base included),
``comm_bytes`` what the main channel sent this step (maps and teammate records,
all links), ``control_bytes`` the same for the control channel; the information
latency at the base is the age of each alive robot's newest report the base
holds (its max and mean over robots, as the original logs it), and each robot's
``base_contact`` is the last step its data reached the base (-1: never).
A :class:`StepRecord` is one row of ``metrics.csv``, made by :func:`measure_step` for
live runs (``Simulation.measure``) and replays (``output.runlog.Replay``) alike;
:class:`Milestones` remembers the first step each fraction crossed 0.5/0.9/0.95.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from mresim_phys.knowledge.coverage import Coverage
from mresim_phys.types import FREE, BeliefGrid, BoolGrid

THRESHOLDS = (0.5, 0.9, 0.95)


@dataclass(frozen=True)
class RobotRecord:
    """One robot in one step."""

    name: str
    distance: float
    state: str
    base_contact: int = -1


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
    comm_bytes: int = 0
    control_links: int = 0
    control_bytes: int = 0
    latency_max: float = 0.0
    latency_mean: float = 0.0
    stale: int | None = None  # cells some robot's map holds wrong now ('latest' beliefs only)
    # runs with faults (knowledge.robustness): failures so far, cells they lost (summed over
    # failures), lost cells the team has not known again yet; None: no such columns
    robustness: tuple[int, int, int] | None = None
    # the same fractions over the free cells 4-connected to the starts (None: not measured,
    # a replay of a log older than the explorable area)
    explored_connected: float | None = None
    known_at_base_connected: float | None = None

    def csv_row(self) -> list[str]:
        """Values in :func:`csv_header` order, floats as exact round-trip text."""
        row = [
            str(self.step),
            repr(self.explored),
            repr(self.known_at_base),
            repr(self.distance),
            str(self.alive),
            str(self.links),
            str(self.comm_bytes),
            str(self.control_links),
            str(self.control_bytes),
            repr(self.latency_max),
            repr(self.latency_mean),
        ]
        if self.explored_connected is not None:
            row += [repr(self.explored_connected), repr(self.known_at_base_connected)]
        row += [repr(r.distance) for r in self.robots]
        row += [r.state for r in self.robots]
        row += [str(r.base_contact) for r in self.robots]
        row = row if self.stale is None else [*row, str(self.stale)]
        return row if self.robustness is None else [*row, *map(str, self.robustness)]


ROBUSTNESS_COLUMNS = ["failures", "knowledge_lost", "lost_unrecovered"]
CONNECTED_COLUMNS = ["explored_connected", "known_at_base_connected"]


def csv_header(
    robot_names: list[str], stale: bool = False, faults: bool = False, connected: bool = True
) -> list[str]:
    """Column names of ``metrics.csv``: the fixed columns, the ``connected`` ones (left out
    only by replays of logs older than them), the per-robot ones, ``stale`` for a world
    that changes, then the robustness columns for a run with faults, last."""
    return (
        ["step", "explored", "known_at_base", "distance", "alive", "links"]
        + ["comm_bytes", "control_links", "control_bytes", "latency_max", "latency_mean"]
        + (CONNECTED_COLUMNS if connected else [])
        + [f"distance_{n}" for n in robot_names]
        + [f"state_{n}" for n in robot_names]
        + [f"base_contact_{n}" for n in robot_names]
        + (["stale"] if stale else [])
        + (ROBUSTNESS_COLUMNS if faults else [])
    )


def measure_step(
    step: int,
    coverage: Coverage,
    known_at_base: float,
    robots: Sequence[RobotRecord],
    links: np.ndarray,
    *,
    control_links: np.ndarray | None,
    comm_bytes: int,
    control_bytes: int,
    latency: tuple[float, float],
    robustness: tuple[int, int, int] | None = None,
    known_at_base_connected: float | None = None,
) -> StepRecord:
    """The step's row of metrics, for a live run and a replay alike.

    Args:
        step: The step number.
        coverage: The team coverage, settled for this step (``explored``).
        known_at_base: The running share of explorable cells the base holds FREE.
        robots: Every robot's record, in scenario order (a ``failed`` one is not alive).
        links: (n, n) bool main-channel links (index 0 = base).
        control_links: (n, n) bool control-channel links, or None without that channel.
        comm_bytes: Main-channel bytes sent this step.
        control_bytes: Control-channel bytes sent this step.
        latency: (max, mean) age of the robots' newest reports at the base.
        robustness: (failures, knowledge_lost, lost_unrecovered) in a run with faults.
        known_at_base_connected: The same share over the coverage's connected cells.
    """
    connected = coverage.fraction_connected
    return StepRecord(
        step=step,
        explored=min(coverage.fraction, 1.0),
        known_at_base=known_at_base,
        distance=sum(r.distance for r in robots),
        alive=sum(r.state != "failed" for r in robots),
        links=int(np.triu(links).sum()),
        robots=tuple(robots),
        comm_bytes=comm_bytes,
        control_links=0 if control_links is None else int(np.triu(control_links).sum()),
        control_bytes=control_bytes,
        latency_max=latency[0],
        latency_mean=latency[1],
        stale=getattr(coverage, "stale", None),
        robustness=robustness,
        explored_connected=None if connected is None else min(connected, 1.0),
        known_at_base_connected=None if connected is None else known_at_base_connected,
    )


def update_known_at_base(
    previous: tuple[float, float | None],
    base_belief: BeliefGrid,
    coverage: Coverage,
    monotone: bool = True,
) -> tuple[float, float | None]:
    """(``known_at_base``, ``known_at_base_connected``) once the base heard news: the share
    of ``coverage``'s counted cells (and of its connected ones; None without them) FREE in
    ``base_belief``, never below ``previous`` (unless not ``monotone``: with 'latest'
    beliefs the base's map can lose a cell a newer observation closed)."""
    free = base_belief == FREE
    counted = share(previous[0], free, coverage.reachable, coverage.total, monotone)
    if coverage.connected is None:
        return counted, None
    connected = coverage.connected, coverage.total_connected
    return counted, share(previous[1] or 0.0, free, *connected, monotone)


def share(previous: float, free: BoolGrid, cells: BoolGrid, total: int, monotone: bool) -> float:
    """The share of ``cells`` (``total`` of them) that are ``free``, at least ``previous``
    if ``monotone``."""
    fraction = min(np.count_nonzero(free & cells) / total if total else 1.0, 1.0)
    return float(max(previous, fraction) if monotone else fraction)


def base_latency(step: int, heard: dict[str, int], robots: list[str]) -> tuple[float, float]:
    """(max, mean) age at ``step`` of the newest report the base holds from each robot.

    ``heard`` maps a robot name to the step of its newest report at the base; a
    robot never heard from counts from step 0.

    >>> base_latency(10, {"A": 8}, ["A", "B"])
    (10.0, 6.0)
    """
    if not robots:
        return 0.0, 0.0
    ages = [float(step - heard.get(name, 0)) for name in robots]
    return max(ages), sum(ages) / len(ages)


def no_milestones() -> dict[str, int | None]:
    """Every threshold, none reached yet."""
    return dict.fromkeys(map(str, THRESHOLDS))


@dataclass
class Milestones:
    """First step at which ``explored`` / ``known_at_base`` (and their ``_connected``
    versions) reached each threshold."""

    explored: dict[str, int | None] = field(default_factory=no_milestones)
    known_at_base: dict[str, int | None] = field(default_factory=no_milestones)
    explored_connected: dict[str, int | None] = field(default_factory=no_milestones)
    known_at_base_connected: dict[str, int | None] = field(default_factory=no_milestones)

    def update(self, record: StepRecord) -> None:
        """Note thresholds first crossed by ``record``."""
        for name in ("explored", "known_at_base", "explored_connected", "known_at_base_connected"):
            value: float | None = getattr(record, name)
            table = getattr(self, name)
            for threshold in THRESHOLDS:
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
        "final_explored_connected": last.explored_connected,
        "final_known_at_base_connected": last.known_at_base_connected,
        "steps_to_explored_connected": dict(milestones.explored_connected),
        "steps_to_known_at_base_connected": dict(milestones.known_at_base_connected),
    }


@dataclass
class StallWatch:
    """When the run last made progress: a gain of ``gain`` in explored or known at base.

    The run is stalled once ``window`` steps have passed since the last step at which
    either fraction rose by at least ``gain`` above its value at the progress before
    (``stop.stalled_for`` / ``stop.stalled_gain``). Slow, steady gains add up: 0.01 %
    a step for ten steps is a gain of 0.1 %.
    """

    window: int | None
    gain: float
    explored: float = 0.0
    known_at_base: float = 0.0
    last_progress: int = 0

    def update(self, record: StepRecord) -> None:
        """Note progress made by ``record``."""
        gained = max(record.explored - self.explored, record.known_at_base - self.known_at_base)
        if record.step == 0 or gained >= self.gain:
            self.explored, self.known_at_base = record.explored, record.known_at_base
            self.last_progress = record.step

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

    def update(self, record: StepRecord) -> None:
        """Add one step."""
        self.comm_bytes += record.comm_bytes
        self.control_bytes += record.control_bytes
        self.link_steps += record.links
        self.latency_max = max(self.latency_max, record.latency_max)
        self.latency_sum += record.latency_mean
        self.steps += 1

    def summary(self) -> dict[str, float | int]:
        """The totals as JSON-ready numbers."""
        return {
            "comm_bytes": self.comm_bytes,
            "control_bytes": self.control_bytes,
            "mean_links": self.link_steps / self.steps if self.steps else 0.0,
            "latency_max": self.latency_max,
            "latency_mean": self.latency_sum / self.steps if self.steps else 0.0,
        }


@dataclass
class Curves:
    """The explored and known-at-base curves of the run, step by step (for their areas)."""

    explored: list[float] = field(default_factory=list)
    known_at_base: list[float] = field(default_factory=list)

    def update(self, record: StepRecord) -> None:
        """Add one step (steps come in order from 0)."""
        self.explored.append(record.explored)
        self.known_at_base.append(record.known_at_base)


def normalised_area(curve: Sequence[float], steps: int | None = None) -> float:
    """Area under ``curve`` (values at steps 0, 1, ...) by the trapezoid rule, divided by
    the number of steps: 1.0 for a curve at 1 from the start. With ``steps`` beyond the
    curve's end, its last value holds until then (a run that stopped early keeps what it
    knew); a one-point curve's area is its value.

    >>> normalised_area([0.0, 0.5, 1.0])
    0.5
    >>> normalised_area([0.0, 1.0], steps=3)
    0.8333333333333334
    """
    values = list(curve)
    if steps is not None and steps + 1 > len(values) and values:
        values += [values[-1]] * (steps + 1 - len(values))
    if len(values) < 2:
        return float(values[0]) if values else 0.0
    inner = sum(values[1:-1])
    return float((values[0] / 2 + inner + values[-1] / 2) / (len(values) - 1))
