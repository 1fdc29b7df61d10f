"""Fault models (phase 0, input): the ``faults:`` block of a scenario, validated.

* ``random``: failures at random steps per robot, from a constant hazard (``mtbf``:
  exponential times between failures, in steps), a Weibull (``shape``, ``scale``: infant
  mortality below shape 1, wear-out above) or a per-step ``probability``; options
  ``robots`` (names or ``all``), ``part``, ``max_failures``, ``after``, ``until`` and
  ``recover_after`` (steps until the part works again; null: never).
* ``battery``: ``{capacity, per_cell, per_scan, per_message}``: a level that drains with
  distance moved, scans and messages sent; at 0 the robot fails.
* ``hazards``: regions (``world/shapes.py``) where each step spent inside fails the robot
  (or a part) with a ``probability``.
* ``fail_if_out_of_contact_for``: a robot fails after this many steps without a link.

What fails (``part``) is shared with scheduled ``fail`` events: ``robot``, ``drive``,
``sensor``, ``radio`` or ``degraded`` (with ``speed_factor`` and/or ``range_factor``).
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from mresim_phys.strict import Strict
from mresim_phys.world.parts import (
    FaultPart,
    LocalizationMode,
    check_localization,
    check_part,
    distance_field,
    factor_field,
    factors_of,
    mode_field,
    part_field,
)
from mresim_phys.world.shapes import Region

Robots = list[str] | Literal["all"]


class PartSpec(Strict):
    """What a fault breaks: a part, and a degraded robot's factors."""

    part: FaultPart = part_field()
    speed_factor: float | None = factor_field("the robot's speed")
    range_factor: float | None = factor_field("the sensor range")
    mode: LocalizationMode | None = mode_field()
    distance: float | None = distance_field()
    robots: Robots = Field("all", description="Names of the robots it may strike, or 'all'.")

    @model_validator(mode="after")
    def _part(self) -> PartSpec:
        check_part(self.part, self.speed_factor, self.range_factor)
        check_localization(self.part, self.mode, self.distance)
        return self

    @property
    def factors(self) -> tuple[float, float]:
        """(speed factor, range factor)."""
        return factors_of(self.speed_factor, self.range_factor)


class RandomFaultSpec(PartSpec):
    """Failures at random steps, per robot: exactly one of ``mtbf``, ``shape`` and
    ``scale`` (Weibull), or ``probability``."""

    mtbf: float | None = Field(
        None, gt=0, description="Mean steps between failures (constant hazard, exponential)."
    )
    shape: float | None = Field(None, gt=0, description="Weibull shape (<1 early, >1 wear-out).")
    scale: float | None = Field(None, gt=0, description="Weibull scale, steps.")
    probability: float | None = Field(
        None, ge=0, le=1, description="Probability of a failure at each step."
    )
    max_failures: int | None = Field(
        None, ge=1, description="Most failures per robot (null: no limit)."
    )
    after: int = Field(0, ge=0, description="Failure clocks start at this step.")
    until: int | None = Field(None, ge=1, description="No failure after this step (null: none).")
    recover_after: int | None = Field(
        None, ge=1, description="Steps until the part works again (null: never)."
    )

    @model_validator(mode="after")
    def _jumps_recur(self) -> RandomFaultSpec:
        if self.mode == "jump" and self.recover_after is not None:
            raise ValueError("a localisation jump is over at once: give no recover_after")
        return self

    @model_validator(mode="after")
    def _one_law(self) -> RandomFaultSpec:
        laws = [self.mtbf is not None, self.shape is not None or self.scale is not None]
        laws.append(self.probability is not None)
        if sum(laws) != 1:
            raise ValueError(
                "give exactly one failure law: mtbf, or shape and scale (Weibull), or probability"
            )
        if (self.shape is None) != (self.scale is None):
            raise ValueError("a Weibull law needs both 'shape' and 'scale'")
        if self.until is not None and self.until <= self.after:
            raise ValueError(f"'until' ({self.until}) must come after 'after' ({self.after})")
        return self


class BatterySpec(Strict):
    """A battery per robot: it drains as the robot moves, scans and sends; empty, it fails."""

    capacity: float = Field(gt=0, description="Charge at the start (any unit).")
    per_cell: float = Field(1.0, ge=0, description="Charge used per cell moved.")
    per_scan: float = Field(0.0, ge=0, description="Charge used per scan.")
    per_message: float = Field(
        0.0, ge=0, description="Charge used per message sent (to one agent in one step)."
    )
    robots: Robots = Field("all", description="Names of the robots that have one, or 'all'.")


class HazardSpec(PartSpec):
    """A zone (fire, water) where each step spent inside fails the robot with a probability."""

    region: Region = Field(
        description="{box: [x0, y0, x1, y1]}, {circle: [x, y, r]}, {polygon: [[x, y], ...]}"
        " or {mask: file.png} (dark pixels; the map's size; relative to the scenario file)."
    )
    probability: float = Field(ge=0, le=1, description="Probability of failing per step inside.")


class FaultsSpec(Strict):
    """Random failures, a battery, hazard zones and the out-of-contact rule."""

    random: list[RandomFaultSpec] = Field(
        default_factory=list, description="Random failure laws: see 'faults.random[i]'."
    )
    battery: BatterySpec | None = Field(None, description="A battery per robot (null: none).")
    hazards: list[HazardSpec] = Field(
        default_factory=list, description="Hazard zones: see 'faults.hazards[i]'."
    )
    fail_if_out_of_contact_for: int | None = Field(
        None, ge=1, description="A robot fails after this many steps without a link (null: never)."
    )

    def robot_lists(self) -> list[tuple[str, Robots]]:
        """(field, robots) for every list of robot names in the block."""
        out: list[tuple[str, Robots]] = [
            (f"faults.random[{k}].robots", r.robots) for k, r in enumerate(self.random)
        ]
        out += [(f"faults.hazards[{k}].robots", h.robots) for k, h in enumerate(self.hazards)]
        if self.battery is not None:
            out.append(("faults.battery.robots", self.battery.robots))
        return out


def chosen(robots: Robots, name: str) -> bool:
    """Whether ``robots`` (a list of names or 'all') includes the robot ``name``."""
    return robots == "all" or name in robots
