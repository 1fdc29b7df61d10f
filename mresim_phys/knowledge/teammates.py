"""Knowledge (phase 3c): what one agent last heard about another, and what strategies send.

A :class:`TeammateInfo` is the record agents exchange about themselves and pass
on about others (newest wins). Besides the fixed fields (where, heading for
what, state, role, when) it carries an optional :class:`Payload`: typed data a
strategy fills through its ``Decision`` (a rendezvous agreement, a relay
request, a role offer) that travels only along links, hop by hop with the
record, and is counted in bytes like everything else that is sent.

The payload a robot sends is a per-robot feature (``features.py``): :data:`PAYLOAD`, its
state in ``Robot.features["payload"]`` from the decision that gave it until the next one
(no entry: it sends none). Its strategy sees it in its view; snapshots and logs do not
record it (a teammate's copy travels in the records, counted in comm bytes).

The teammates an agent presumes lost (:func:`presumed_lost`: no news of them for longer
than the run's limit) are the feature :data:`LOST` (key ``lost``), a value the views
compute from the agent's records when they are built (:func:`with_lost`; no state is kept):
its strategy sees it (``RobotView.lost``), snapshots record it while it is not empty (a
failed robot presumes nothing; the base its own), the run log stores it as a sorted list
(``presumed_lost`` in logs of version 6 or older), and frames with the ``presumed_lost``
layer label the agent with it (``A lost?B,C``).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from mresim_phys.features import NameSetFeature, PlainFeature

BASE_NAME = "base"
RECORD_BYTES = 40  # name, position, goal, state, role and step of one record
SCALAR_BYTES = 8  # a number (int, float, bool) in a payload
POINT_BYTES = 16  # an (x, y) pair of floats


def value_bytes(value: Any) -> int:
    """Bytes a payload value takes on the radio: numbers 8, points 16, text its UTF-8 length.

    >>> value_bytes((1.0, 2.0)), value_bytes("abc"), value_bytes([(0.0, 0.0)] * 3)
    (16, 3, 48)
    """
    if value is None:
        return 0
    if isinstance(value, (bool, int, float, np.number)):
        return SCALAR_BYTES
    if isinstance(value, str):
        return len(value.encode("utf-8"))
    if isinstance(value, np.ndarray):
        return int(value.nbytes)
    if isinstance(value, Payload):
        return value.nbytes()
    if isinstance(value, (tuple, list)):
        if len(value) == 2 and all(isinstance(v, (int, float)) for v in value):
            return POINT_BYTES
        return sum(value_bytes(v) for v in value)
    if isinstance(value, dict):
        return sum(value_bytes(k) + value_bytes(v) for k, v in value.items())
    raise TypeError(f"a payload cannot carry a {type(value).__name__}")


@dataclass(frozen=True)
class Payload:
    """Base for what a strategy sends its teammates: subclass it as a frozen dataclass.

    Its size on the radio is the sum of its fields' sizes (:func:`value_bytes`);
    override :meth:`nbytes` for a tighter encoding.
    """

    def nbytes(self) -> int:
        """Bytes this payload adds to a teammate record."""
        return sum(value_bytes(getattr(self, f.name)) for f in dataclasses.fields(self))


@dataclass(frozen=True)
class TeammateInfo:
    """What one agent last heard about another: where it was, where it was heading, when.

    ``step`` is when the record was true (its sender's step); ``learned`` the step at
    which the holder received it (-1 for an agent's own record, not yet sent).
    ``payload`` is what the teammate's strategy asked to send with it; ``broken`` the
    parts that did not work when it was sent (``drive``, ``sensor``, ``radio``,
    ``degraded``: a robot with a failed part still talks and says so; its size is part of
    the state's bytes).
    """

    name: str
    position: tuple[float, float]
    goal: tuple[float, float] | None
    state: str
    role: str
    step: int
    learned: int = -1
    payload: Payload | None = None
    broken: tuple[str, ...] = ()

    def nbytes(self) -> int:
        """Bytes this record takes on the radio."""
        extra = self.payload.nbytes() if self.payload is not None else 0
        return RECORD_BYTES + extra

    def learned_at(self, step: int) -> TeammateInfo:
        """This record as received at ``step``: ``dataclasses.replace(self, learned=step)``
        without re-running ``__init__`` (0.4 vs 3 us; every exchange copies one record per
        pair of linked agents and teammate, n^2 a step). A record already stamped ``step``
        (passed on within the step's exchange) is itself: records are frozen, so agents
        may share one."""
        if self.learned == step:
            return self
        copy = object.__new__(TeammateInfo)
        copy.__dict__.update(self.__dict__)
        copy.__dict__["learned"] = step
        return copy


def presumed_lost(teammates: dict[str, TeammateInfo], step: int, silence: int) -> frozenset[str]:
    """Teammates whose newest record is older than ``silence`` steps (the base never counts).

    >>> old = TeammateInfo("B", (0.0, 0.0), None, "active", "explorer", step=1)
    >>> sorted(presumed_lost({"B": old}, step=500, silence=100))
    ['B']
    """
    return frozenset(
        name
        for name, record in teammates.items()
        if name != BASE_NAME and step - record.step > silence
    )


class PresumedLost(NameSetFeature[frozenset[str]]):
    """The teammates an agent presumes lost (module docstring)."""

    key = "lost"
    omit_empty = True
    layer = "presumed_lost"

    def value(self, state: frozenset[str]) -> frozenset[str]:
        """The names themselves."""
        return state

    def label(self, value: frozenset[str]) -> str:
        """`` lost?B,C``."""
        return f" lost?{','.join(sorted(value))}"


LOST = PresumedLost()


def with_lost(states: Mapping[str, Any], lost: frozenset[str]) -> dict[str, Any]:
    """An agent's feature ``states`` with the teammates it presumes lost now."""
    return {**states, LOST.key: lost}


class SentPayload(PlainFeature[Payload]):
    """The payload a robot's strategy sends with its record (module docstring); its value
    is the (frozen) payload itself."""

    key = "payload"
    recorded = False


PAYLOAD = SentPayload()


def keep_payload(states: dict[str, Any], payload: Payload | None) -> None:
    """Make ``payload`` the one a robot with feature ``states`` sends (None: none)."""
    if payload is None:
        states.pop(PAYLOAD.key, None)
    else:
        states[PAYLOAD.key] = payload
