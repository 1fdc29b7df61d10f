"""Localisation models (phase 0, input): a robot's ``localization:`` block, validated.

Per robot or in ``team:`` (a robot's own block replaces the team's key by key)::

    localization:
      odometry: {alpha: [0.02, 0.01, 0.02, 0.01]}   # a1..a4 (odometry.py)
      corrections:
        - {kind: base, within: 20, sigma: 0.5}         # a position fix near the base
        - {kind: beacons, positions: [[120, 40]], range: 40, sigma: 0.5}
        - {kind: teammate, sigma_range: 0.3, sigma_bearing_deg: 2}
        - {kind: scan_matching, window: 3, every: 1}

A robot without the block knows its pose exactly, as before. Which correction does what,
with its formula, is in docs/localization.md; where the beacons stand is checked against
the map by ``build.py`` (off the map, in a wall: exit 2).
"""

from __future__ import annotations

from functools import cached_property
from typing import Annotated, Any, Literal

from pydantic import Discriminator, Field, Tag, field_validator

from mresim_phys.strict import Strict

Point = tuple[float, float]


class OdometrySpec(Strict):
    """The odometry motion model's noise (Thrun, Burgard and Fox, table 5.6)."""

    alpha: tuple[float, float, float, float] = Field(
        (0.0, 0.0, 0.0, 0.0),
        description=(
            "a1..a4, each >= 0: rotation noise per rotation (rad^2/rad^2) and per"
            " translation (rad^2/cell^2), translation noise per translation"
            " (cell^2/cell^2) and per rotation (cell^2/rad^2); all 0: no drift."
        ),
    )

    @field_validator("alpha")
    @classmethod
    def _non_negative(cls, alpha: tuple[float, ...]) -> tuple[float, ...]:
        bad = [f"a{i + 1} = {a}" for i, a in enumerate(alpha) if not a >= 0]
        if bad:
            raise ValueError(f"odometry alphas must be >= 0 (a variance per motion): {bad}")
        return alpha


class BaseFix(Strict):
    """A position fix whenever the robot is within ``within`` cells of the base station
    (the base is a known landmark), with noise ``sigma``."""

    kind: Literal["base"]
    within: float = Field(20.0, gt=0, description="Cells from the base within which it fixes.")
    sigma: float = Field(0.5, gt=0, description="Standard deviation of the fix, cells.")


class BeaconsFix(Strict):
    """A position fix from each beacon within ``range`` cells in line of sight."""

    kind: Literal["beacons"]
    positions: list[Point] = Field(min_length=1, description="Each beacon's [x, y], cells.")
    range: float = Field(40.0, gt=0, description="Cells within which a beacon is seen.")
    sigma: float = Field(0.5, gt=0, description="Standard deviation of a fix, cells.")


class TeammateFix(Strict):
    """A range and bearing to each teammate linked on the main channel."""

    kind: Literal["teammate"]
    sigma_range: float = Field(0.3, gt=0, description="Range noise, cells.")
    sigma_bearing_deg: float = Field(2.0, gt=0, description="Bearing noise, degrees.")


class ScanMatchFix(Strict):
    """Each ``every``-th scan aligned to the robot's own map before it is folded in."""

    kind: Literal["scan_matching"]
    window: float = Field(3.0, gt=0, le=20, description="Cells searched either side.")
    turn_deg: float = Field(6.0, gt=0, le=45, description="Degrees searched either side.")
    every: int = Field(1, ge=1, description="Match every this many scans.")
    sigma: float = Field(1.0, gt=0, description="The likelihood field's sigma, cells.")


KINDS = ("base", "beacons", "teammate", "scan_matching")


def correction_kind(value: Any) -> str | None:
    """Which correction an entry is: its ``kind`` (None: none of :data:`KINDS`)."""
    kind = value.get("kind") if isinstance(value, dict) else getattr(value, "kind", None)
    return kind if kind in KINDS else None


Correction = Annotated[
    Annotated[BaseFix, Tag("base")]
    | Annotated[BeaconsFix, Tag("beacons")]
    | Annotated[TeammateFix, Tag("teammate")]
    | Annotated[ScanMatchFix, Tag("scan_matching")],
    Discriminator(
        correction_kind,
        custom_error_type="unknown_correction",
        custom_error_message="a correction needs a kind: " + ", ".join(KINDS),
    ),
]


class LocalizationSpec(Strict):
    """A robot that does not know its pose exactly: odometry drift and its corrections."""

    odometry: OdometrySpec = Field(default_factory=OdometrySpec)
    corrections: list[Correction] = Field(
        default_factory=list, description="Corrections, at most one of each kind."
    )

    @cached_property
    def matching(self) -> ScanMatchFix | None:
        """The scan matching correction, if there is one."""
        found = [c for c in self.corrections if isinstance(c, ScanMatchFix)]
        return found[0] if found else None

    @field_validator("corrections")
    @classmethod
    def _one_of_each(cls, corrections: list[Correction]) -> list[Correction]:
        kinds = [c.kind for c in corrections]
        twice = sorted({k for k in kinds if kinds.count(k) > 1})
        if twice:
            raise ValueError(f"one correction of each kind; given twice: {twice}")
        return corrections
