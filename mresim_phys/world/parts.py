"""World (phase 0, events): what can fail in a robot, shared by fail events and fault models.

A scheduled ``fail`` event (``world/events.py``) and the ``faults:`` block
(``faults/spec.py``) both name a ``part``: ``robot``, ``drive``, ``sensor``, ``radio`` or
``degraded`` (with ``speed_factor`` and/or ``range_factor``). The field definitions and
their checks live here, below both.
"""

from __future__ import annotations

from typing import Any, Literal

from pydantic import Field

FaultPart = Literal["robot", "drive", "sensor", "radio", "degraded"]
PART_TEXT = (
    "What fails: 'robot' (no motion, sensing or communication), 'drive' (cannot move),"
    " 'sensor' (no scans), 'radio' (cannot communicate) or 'degraded' (speed and/or sensor"
    " range scaled by speed_factor / range_factor)."
)


def part_field() -> Any:
    """The ``part`` field of a fault (a scheduled failure, a random one, a hazard)."""
    return Field("robot", description=PART_TEXT)


def factor_field(what: str) -> Any:
    """A ``speed_factor`` / ``range_factor`` field of a ``degraded`` part."""
    return Field(None, gt=0, le=1, description=f"part: degraded: {what} is scaled by this.")


def check_part(part: str, speed: float | None, sensor_range: float | None) -> None:
    """A ``degraded`` part needs a factor; the factors go with ``degraded`` only."""
    factors = speed is not None or sensor_range is not None
    if part == "degraded" and not factors:
        raise ValueError("part 'degraded' needs speed_factor and/or range_factor in (0, 1]")
    if part != "degraded" and factors:
        raise ValueError(f"speed_factor and range_factor go with part 'degraded', not {part!r}")


def factors_of(speed: float | None, sensor_range: float | None) -> tuple[float, float]:
    """(speed factor, range factor) of a part; 1 where not given."""
    return (1.0 if speed is None else speed, 1.0 if sensor_range is None else sensor_range)
