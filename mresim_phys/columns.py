"""Metric columns (phase 7, metrics): every column of ``metrics.csv``, one registration each.

A step's facts are one :class:`~mresim_phys.metrics.StepRecord`, made by
:func:`~mresim_phys.metrics.measure_step` for a live run and for a replay of its log alike.
A :class:`Column` is a name and a value computed from those facts: one value per step, or
(``per_robot``) one per robot, written as ``<prefix>_<robot>``. ``metrics.csv``'s header and
rows, the milestones, the stall rule, the curves and the viewer's chart all read columns
(:func:`value_of`), so a column registered once is written by the run and recomputed by
``mresim replay --metrics`` by construction.

The default columns are the built-in ones registered here without ``optional``, in the
order of registration (today's ``metrics.csv``). A column that ``needs`` a flag of the
run's :class:`Layout` is written only when the run has it: ``connected`` (the fractions
over the 4-connected free cells; left out by replays of logs older than them), ``latest``
(a world that changes: ``stale``), ``faults`` (the robustness columns). Optional columns,
built in or from third-party packages (entry-point group ``mresim_phys.metrics``, or a
``package.module:Class`` reference), are written after the defaults, in the order a
scenario names them under ``metrics.columns``. Writing one: ``docs/metric-columns.md``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import cache
from typing import TYPE_CHECKING, ClassVar, TypeAlias, cast

import numpy as np

from mresim_phys.plugin import Family, Plugin, PluginParams
from mresim_phys.registry import Registry

if TYPE_CHECKING:  # the facts a column reads; validating a scenario names columns only
    from mresim_phys.metrics import StepRecord

Scalar: TypeAlias = int | float | str | None
Value: TypeAlias = Scalar | Sequence[Scalar]
FLAGS = ("connected", "latest", "faults")
LOCALIZATION_COLUMNS = (
    "pose_error",
    "heading_error",
    "pose_error_mean",
    "pose_error_max",
)  # what a run's layout may have
RADIO_COLUMNS = (
    "backlog",
    "bytes_offered",
    "bytes_sent",
    "bytes_delivered",
    "bytes_to_base",
    "connected_to_base",
)  # a run whose main channel has radio options (comms/radio_feature.py)
BEAM_COLUMN = "noisy_readings"  # a run with a beam-model laser (readings_feature.py)
CLOCK_COLUMN = "decisions"  # a run with a robot clock (clocks/feature.py)
TEAM_COLUMNS = ("overlap", "workload_cv", "discovered")  # metrics.team (discovery_feature.py)
MEETING_COLUMNS = (
    "meetings_planned",
    "meetings_kept",
    "meetings_missed",
    "meetings_pending",
)  # a run whose strategies plan meetings (meetings/columns.py)


class ColumnParams(PluginParams):
    """A column takes no parameters."""


class Column(Plugin):
    """A metric column: ``name`` (its registry key, and its header for a per-step column),
    ``per_robot`` (one value per robot, headed ``<prefix>_<robot>``), ``needs`` (a
    :class:`Layout` flag without which the run has no such column) and ``optional``
    (written only when a scenario asks for it)."""

    name: ClassVar[str]
    Params: ClassVar[type[ColumnParams]] = ColumnParams
    per_robot: ClassVar[bool] = False
    prefix: ClassVar[str] = ""  # a per-robot column's header prefix ('' : its name)
    needs: ClassVar[str | None] = None
    optional: ClassVar[bool] = False

    def __init__(self, params: ColumnParams | None = None) -> None:
        super().__init__(params or ColumnParams())

    def value(self, record: StepRecord) -> Value:
        """The column's value at the step ``record`` holds the facts of (a per-robot
        column: a sequence in the robots' order)."""
        raise NotImplementedError

    def header(self, robots: Sequence[str]) -> list[str]:
        """The column's names in the header."""
        if not self.per_robot:
            return [self.name]
        return [f"{self.prefix or self.name}_{robot}" for robot in robots]

    def cells(self, record: StepRecord) -> list[str]:
        """The column's text in the row of ``record``."""
        value = self.value(record)
        if self.per_robot:
            assert isinstance(value, Sequence) and not isinstance(value, str)
            return [text(v) for v in value]
        return [text(value)]  # type: ignore[arg-type]


COLUMNS: Registry[Column] = Registry(
    "metric column", "mresim_phys.metrics", Family(Column, ColumnParams)
)


def text(value: Scalar) -> str:
    """A value as ``metrics.csv`` writes it: floats as exact round-trip text, nothing as ''.

    >>> text(0.1), text(3), text("done"), text(None)
    ('0.1', '3', 'done', '')
    """
    if value is None:
        return ""
    return repr(value) if isinstance(value, float) else str(value)


def column(
    name: str,
    *,
    per_robot: bool = False,
    prefix: str = "",
    needs: str | None = None,
    optional: bool = False,
    register: bool = True,
) -> Callable[[Callable[[StepRecord], Value]], type[Column]]:
    """Decorator making a :class:`Column` of a function of the step's facts (and adding it
    to :data:`COLUMNS` unless not ``register``: a third-party column is named by an entry
    point or a ``module:Class`` reference instead)."""
    if needs is not None and needs not in FLAGS:
        raise ValueError(f"column {name!r}: needs {needs!r} is none of {', '.join(FLAGS)}")

    def make(function: Callable[[StepRecord], Value]) -> type[Column]:
        attrs = {
            "name": name,
            "per_robot": per_robot,
            "prefix": prefix,
            "needs": needs,
            "optional": optional,
            "value": lambda self, record: function(record),
            "__doc__": function.__doc__,
            "__module__": function.__module__,
            "__qualname__": function.__qualname__,
        }
        cls = cast("type[Column]", type(function.__name__, (Column,), attrs))
        return COLUMNS.register(cls) if register else cls

    return make


@cache
def column_named(name: str) -> Column:
    """The column registered as ``name`` (or a ``module:Class`` reference), built once."""
    return COLUMNS.make(name)


def value_of(name: str, record: StepRecord) -> Value:
    """Column ``name``'s value at the step of ``record``."""
    return column_named(name).value(record)


@dataclass(frozen=True)
class Layout:
    """The columns of one run's ``metrics.csv``: its robots (scenario order), the flags it
    has (:data:`FLAGS`) and the optional columns its scenario asked for (in that order)."""

    robots: tuple[str, ...]
    flags: frozenset[str] = frozenset({"connected"})
    extra: tuple[str, ...] = ()

    @classmethod
    def of(
        cls,
        robots: Sequence[str],
        *,
        latest: bool,
        faults: bool,
        connected: bool = True,
        extra: Sequence[str] = (),
    ) -> Layout:
        """The layout of a run with these flags."""
        named = {"connected": connected, "latest": latest, "faults": faults}
        flags = frozenset(flag for flag, on in named.items() if on)
        return cls(tuple(robots), flags, tuple(extra))

    def columns(self) -> list[Column]:
        """The run's columns, in order."""
        chosen = [column_named(n) for n in (*DEFAULTS, *self.extra)]
        return [c for c in chosen if c.needs is None or c.needs in self.flags]

    def header(self) -> list[str]:
        """``metrics.csv``'s first row."""
        return [name for c in self.columns() for name in c.header(self.robots)]

    def row(self, record: StepRecord) -> list[str]:
        """``metrics.csv``'s row of ``record``."""
        return [cell for c in self.columns() for cell in c.cells(record)]


# The default columns, in metrics.csv's order (module docstring of metrics.py: meanings).


@column("step")
def step(r: StepRecord) -> int:
    """The step number."""
    return r.step


@column("explored")
def explored(r: StepRecord) -> float:
    """Share of the explorable cells the team holds FREE."""
    return r.explored


@column("known_at_base")
def known_at_base(r: StepRecord) -> float:
    """Share of the explorable cells the base station holds FREE."""
    return r.known_at_base


@column("distance")
def distance(r: StepRecord) -> float:
    """Cells travelled by the whole team so far."""
    return r.distance


@column("alive")
def alive(r: StepRecord) -> int:
    """Robots not failed."""
    return r.alive


@column("links")
def links(r: StepRecord) -> int:
    """Linked agent pairs on the main channel (the base included)."""
    return r.links


@column("comm_bytes")
def comm_bytes(r: StepRecord) -> int:
    """Bytes the main channel sent this step."""
    return r.comm_bytes


@column("control_links")
def control_links(r: StepRecord) -> int:
    """Linked agent pairs on the control channel."""
    return r.control_links


@column("control_bytes")
def control_bytes(r: StepRecord) -> int:
    """Bytes the control channel sent this step."""
    return r.control_bytes


@column("latency_max")
def latency_max(r: StepRecord) -> float:
    """Age of the oldest newest report of an alive robot at the base."""
    return r.latency_max


@column("latency_mean")
def latency_mean(r: StepRecord) -> float:
    """Mean age of the alive robots' newest reports at the base."""
    return r.latency_mean


@column("explored_connected", needs="connected")
def explored_connected(r: StepRecord) -> float | None:
    """``explored`` over the free cells 4-connected to the starts."""
    return r.explored_connected


@column("known_at_base_connected", needs="connected")
def known_at_base_connected(r: StepRecord) -> float | None:
    """``known_at_base`` over the free cells 4-connected to the starts."""
    return r.known_at_base_connected


@column("robot_distance", per_robot=True, prefix="distance")
def robot_distance(r: StepRecord) -> list[float]:
    """Cells each robot travelled so far."""
    return [robot.distance for robot in r.robots]


@column("robot_state", per_robot=True, prefix="state")
def robot_state(r: StepRecord) -> list[str]:
    """Each robot's state (exploring, returning, done, failed, ...)."""
    return [robot.state for robot in r.robots]


@column("robot_base_contact", per_robot=True, prefix="base_contact")
def robot_base_contact(r: StepRecord) -> list[int]:
    """The last step each robot's data reached the base (-1: never)."""
    return [robot.base_contact for robot in r.robots]


@column("stale", needs="latest")
def stale(r: StepRecord) -> int | None:
    """Cells some robot's map holds wrong now (a world that changes)."""
    return r.stale


@column("failures", needs="faults")
def failures(r: StepRecord) -> int | None:
    """Robot failures so far (knowledge/robustness.py)."""
    return None if r.robustness is None else r.robustness[0]


@column("knowledge_lost", needs="faults")
def knowledge_lost(r: StepRecord) -> int | None:
    """Cells the failures lost (summed over failures)."""
    return None if r.robustness is None else r.robustness[1]


@column("lost_unrecovered", needs="faults")
def lost_unrecovered(r: StepRecord) -> int | None:
    """Lost cells the team has not known again yet."""
    return None if r.robustness is None else r.robustness[2]


# Optional columns: written when a scenario names them under metrics.columns.


@column("robots_done", optional=True)
def robots_done(r: StepRecord) -> int:
    """Robots in state ``done`` (parked: no frontier left they can reach)."""
    return sum(robot.state == "done" for robot in r.robots)


@column("base_links", optional=True)
def base_links(r: StepRecord) -> int | None:
    """Robots linked to the base directly on the main channel this step."""
    return None if r.link_matrix is None else int(np.count_nonzero(r.link_matrix[0, 1:]))


@column("longest_path", optional=True)
def longest_path(r: StepRecord) -> float:
    """The distance the robot that drove farthest has driven (cells)."""
    return max((robot.distance for robot in r.robots), default=0.0)


@column("robot_base_link", per_robot=True, prefix="base_link", optional=True)
def robot_base_link(r: StepRecord) -> list[int]:
    """1 where the robot is linked to the base directly on the main channel this step."""
    if r.link_matrix is None:
        return [0] * len(r.robots)
    return [int(v) for v in r.link_matrix[0, 1 : len(r.robots) + 1]]


DEFAULTS: tuple[str, ...] = tuple(c.name for c in COLUMNS.registered() if not c.optional)
"""The default columns (built in here, not optional), in ``metrics.csv``'s order; a column
registered later (a plugin's) is never a default."""

# Optional columns a feature's own module registers (``features.py``), imported when named.
FEATURE_COLUMNS = {
    "robot_battery": "mresim_phys.faults.battery:robot_battery",
    **{n: f"mresim_phys.localization.feature:{n}" for n in LOCALIZATION_COLUMNS},
    **{n: f"mresim_phys.comms.radio_feature:{n}" for n in RADIO_COLUMNS},
    **{n: f"mresim_phys.meetings.columns:{n}" for n in MEETING_COLUMNS},
    BEAM_COLUMN: "mresim_phys.readings_feature:noisy_readings",
    CLOCK_COLUMN: "mresim_phys.clocks.feature:decisions",
    **{n: f"mresim_phys.discovery_feature:{n}" for n in TEAM_COLUMNS},
}
for _name, _reference in FEATURE_COLUMNS.items():
    COLUMNS.lazy(_name, _reference, ColumnParams)
