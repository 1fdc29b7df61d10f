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
A :class:`StepRecord` holds one step's facts, made by :func:`measure_step` for live
runs (``Simulation.measure``) and replays (``output.runlog.Replay``) alike; the columns of
``metrics.csv`` are computed from it (``columns``), and the run's trackers (milestones,
stall rule, curves, communication totals: ``tracking``) read those columns.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from mresim_phys.knowledge.coverage import Coverage
from mresim_phys.types import FREE, BeliefGrid, BoolGrid

if TYPE_CHECKING:
    from mresim_phys.meeting_board import MeetingBoard

THRESHOLDS = (0.5, 0.9, 0.95)


@dataclass(frozen=True)
class RobotRecord:
    """One robot in one step."""

    name: str
    distance: float
    state: str
    base_contact: int = -1
    features: Mapping[str, Any] = field(default_factory=dict)  # each feature's value


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
    # the (n, n) main-channel links (index 0 = the base) the ``links`` count comes from
    link_matrix: BoolGrid | None = field(default=None, compare=False, repr=False)
    # the rendezvous accounting (meetings/): None in a run whose strategies plan no meetings
    meetings: MeetingBoard | None = None


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
    meetings: MeetingBoard | None = None,
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
        meetings: The rendezvous accounting's board (``meetings/``), if the run has one.
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
        link_matrix=np.array(links, dtype=bool),  # the live array changes in place
        meetings=meetings,
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
