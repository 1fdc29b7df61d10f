"""World (phase 0, events): what can fail in a robot, shared by fail events and fault models.

A scheduled ``fail`` event (``world/events.py``) and the ``faults:`` block
(``faults/spec.py``) both name a ``part``: ``robot``, ``drive``, ``sensor``, ``radio`` or
``degraded`` (with ``speed_factor`` and/or ``range_factor``). The field definitions and
their checks live here, below both.
"""

from __future__ import annotations

from typing import Any, Literal

from pydantic import Field

FaultPart = Literal["robot", "drive", "sensor", "radio", "degraded", "localization"]
LocalizationMode = Literal["frozen", "jump"]
PART_TEXT = (
    "What fails: 'robot' (no motion, sensing or communication), 'drive' (cannot move),"
    " 'sensor' (no scans), 'radio' (cannot communicate), 'degraded' (speed and/or sensor"
    " range scaled by speed_factor / range_factor) or 'localization' (with mode 'frozen':"
    " the believed pose stops following the motion; mode 'jump': it is thrown 'distance'"
    " cells off at once, the kidnapped robot)."
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


def mode_field() -> Any:
    """The ``mode`` field of a localisation fault."""
    return Field(None, description="part: localization: 'frozen' or 'jump'.")


def distance_field() -> Any:
    """The ``distance`` field of a localisation jump."""
    return Field(None, gt=0, description="mode: jump: cells the believed pose is thrown off.")


def check_localization(part: str, mode: str | None, distance: float | None) -> None:
    """A ``localization`` part needs a mode, a jump its distance; neither goes elsewhere."""
    if part == "localization" and mode is None:
        raise ValueError("part 'localization' needs a mode: 'frozen' or 'jump'")
    if part != "localization" and (mode is not None or distance is not None):
        raise ValueError(f"mode and distance go with part 'localization', not {part!r}")
    if mode == "jump" and distance is None:
        raise ValueError("mode 'jump' needs a distance (cells the believed pose is thrown)")
    if mode == "frozen" and distance is not None:
        raise ValueError("distance goes with mode 'jump', not 'frozen'")


def factors_of(speed: float | None, sensor_range: float | None) -> tuple[float, float]:
    """(speed factor, range factor) of a part; 1 where not given."""
    return (1.0 if speed is None else speed, 1.0 if sensor_range is None else sensor_range)
