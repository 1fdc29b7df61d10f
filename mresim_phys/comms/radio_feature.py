"""The radio load of a robot (phase 6b, a per-robot feature): bytes offered, sent, delivered
and queued on bounded links, and the radio metric columns.

Runs whose main channel has a ``capacity``, a ``radio_capacity`` or a ``latency``
(``comms/queued.py``) give every robot the feature ``radio``: the bytes it offered this
step, sent, delivered (its packets that landed this step, wherever they were sent from)
and delivered to the base. It is logged (``[offered, sent, delivered, to_base]`` in each
robot's line of the run log), so a replay recomputes the columns; frames add the bytes
queued beside the robot's name (robot layer ``radio``: ``A q3.1k``) and the viewer's hover
row shows all four.

Columns, written when the main channel has any radio option (docs/communication.md):
``backlog_<robot>`` (bytes offered and not sent this step), ``bytes_offered``,
``bytes_sent``, ``bytes_delivered`` and ``bytes_to_base`` (robots' radios, summed), and
``connected_to_base``, the share of the robots not failed that are in the base's linked
group on the main channel this step (the link matrix; any radio option).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from mresim_phys.columns import RADIO_COLUMNS, column
from mresim_phys.comms.radio_params import RadioSpec
from mresim_phys.features import RobotFeature

if TYPE_CHECKING:
    from mresim_phys.metrics import StepRecord


def radio_columns(spec: RadioSpec) -> tuple[str, ...]:
    """The radio metric columns of a run whose main channel has these options: the byte
    counts when its links are bounded (or replayed from a trace that may bound them), the
    share connected to the base with any option."""
    if spec.bounded or spec.trace is not None:
        return RADIO_COLUMNS
    return RADIO_COLUMNS[-1:] if spec.lossy else ()


@dataclass(frozen=True)
class RadioLoadValue:
    """A robot's bytes in one step: offered, sent, delivered (landed), delivered to the base."""

    offered: int = 0
    sent: int = 0
    delivered: int = 0
    to_base: int = 0

    @property
    def backlog(self) -> int:
        """Bytes offered and not sent this step: what stays queued."""
        return self.offered - self.sent


@dataclass
class RadioCounters:
    """The state the queued exchange writes each step (``QueuedExchange.publish``)."""

    value: RadioLoadValue = RadioLoadValue()


class RadioFeature(RobotFeature[RadioCounters, RadioLoadValue]):
    """A robot's radio load on bounded links (module docstring)."""

    key = "radio"
    layer = "radio"

    def value(self, state: RadioCounters) -> RadioLoadValue:
        """This step's bytes."""
        return state.value

    def encode(self, value: RadioLoadValue) -> Any:
        """``[offered, sent, delivered, to_base]``."""
        return [value.offered, value.sent, value.delivered, value.to_base]

    def decode(self, raw: Any) -> RadioLoadValue:
        """The logged list read back."""
        return RadioLoadValue(*(int(v) for v in raw))

    def label(self, value: RadioLoadValue) -> str:
        """The bytes queued, when there are any: `` q3.1k``."""
        return f" q{kilo(value.backlog)}" if value.backlog > 0 else ""

    def hover(self, value: RadioLoadValue) -> Any:
        """The four counts and the backlog, named."""
        return {
            "offered": value.offered,
            "sent": value.sent,
            "delivered": value.delivered,
            "to_base": value.to_base,
            "backlog": value.backlog,
        }


RADIO = RadioFeature()


def kilo(count: int) -> str:
    """A byte count in short form.

    >>> kilo(950), kilo(3140), kilo(2_500_000)
    ('950', '3.1k', '2.5M')
    """
    if count < 1000:
        return str(count)
    if count < 1_000_000:
        return f"{count / 1000:.1f}k"
    return f"{count / 1_000_000:.1f}M"


def _loads(r: StepRecord) -> list[RadioLoadValue | None]:
    """Each robot's radio load in ``r`` (None: no such feature)."""
    return [RADIO.of(robot) for robot in r.robots]


def _total(r: StepRecord, field: str) -> int | None:
    """The robots' ``field`` summed (None when no robot has the feature)."""
    loads = [v for v in _loads(r) if v is not None]
    return sum(getattr(v, field) for v in loads) if loads else None


@column("backlog", per_robot=True, optional=True)
def backlog(r: StepRecord) -> Sequence[int | None]:
    """Bytes each robot offered and could not send this step (bounded links)."""
    return [None if v is None else v.backlog for v in _loads(r)]


@column("bytes_offered", optional=True)
def bytes_offered(r: StepRecord) -> int | None:
    """Bytes the robots' radios offered this step (bounded links)."""
    return _total(r, "offered")


@column("bytes_sent", optional=True)
def bytes_sent(r: StepRecord) -> int | None:
    """Bytes the robots' radios sent this step (bounded links)."""
    return _total(r, "sent")


@column("bytes_delivered", optional=True)
def bytes_delivered(r: StepRecord) -> int | None:
    """Bytes of the robots' packets that landed this step (bounded links)."""
    return _total(r, "delivered")


@column("bytes_to_base", optional=True)
def bytes_to_base(r: StepRecord) -> int | None:
    """Bytes of the robots' packets that landed at the base this step (bounded links)."""
    return _total(r, "to_base")


@column("connected_to_base", optional=True)
def connected_to_base(r: StepRecord) -> float | None:
    """Share of the robots not failed in the base's linked group on the main channel."""
    if r.link_matrix is None:
        return None
    alive = [i + 1 for i, robot in enumerate(r.robots) if robot.state != "failed"]
    if not alive:
        return 0.0
    return len(base_group(r.link_matrix) & set(alive)) / len(alive)


def base_group(links: np.ndarray) -> set[int]:
    """The agents linked to the base (index 0) directly or through a chain."""
    either = links | links.T
    seen, todo = {0}, [0]
    while todo:
        for other in np.flatnonzero(either[todo.pop()]).tolist():
            if other not in seen:
                seen.add(other)
                todo.append(other)
    return seen - {0}
