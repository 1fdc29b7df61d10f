"""Robot clocks (phase 0, input): a robot's ``clock:`` block, validated.

Per robot or in ``team:`` (a robot's own block replaces the team's key by key)::

    clock:
      act_every: 2          # a slow platform: it moves, decides and scans on every 2nd step
      phase: 1              # ... on steps 1, 3, 5, ... (step t acts when t % act_every == phase)
      decision_period: 5    # its strategy is asked at most once every 5 steps
      compute_delay: {min: 1, max: 3}   # a plan takes effect 1 to 3 steps after it is asked
      scan_period: 2        # it scans on a step at least 2 steps after its last scan

A robot without the block decides, moves and scans on every step, as before. What each
field does, step by step, is in docs/clocks.md; the gates are in ``clocks/gate.py``.
"""

from __future__ import annotations

from typing import Any

from pydantic import Field, field_validator, model_validator

from mresim_phys.strict import Strict

MAX_PERIOD = 100_000  # steps: a period or a delay longer than any run is a mistake


class DelaySpec(Strict):
    """A compute delay drawn per decision, uniformly from ``min`` to ``max`` steps (both
    included), from the robot's stream ``compute-delay``."""

    min: int = Field(0, ge=0, le=MAX_PERIOD, description="Fewest steps a plan waits.")
    max: int = Field(0, ge=0, le=MAX_PERIOD, description="Most steps a plan waits.")

    @model_validator(mode="after")
    def _ordered(self) -> DelaySpec:
        if self.max < self.min:
            raise ValueError(
                f"a compute delay's max ({self.max}) is below its min ({self.min}); give"
                " max >= min (or one integer for a fixed delay)"
            )
        return self


class ClockSpec(Strict):
    """When a robot acts, decides and scans (docs/clocks.md)."""

    act_every: int = Field(
        1, ge=1, le=MAX_PERIOD, description="It moves, decides and scans on every n-th step."
    )
    phase: int = Field(
        0, ge=0, le=MAX_PERIOD, description="Which steps: t acts when t % act_every == phase."
    )
    decision_period: int = Field(
        1, ge=1, le=MAX_PERIOD, description="Steps at least between two asks of its strategy."
    )
    compute_delay: DelaySpec = Field(
        default_factory=DelaySpec,
        description=(
            "Steps from asking its strategy to following the plan: an integer or {min, max}"
            " drawn per decision from the stream compute-delay."
        ),
    )
    scan_period: int = Field(
        1, ge=1, le=MAX_PERIOD, description="Steps at least between two steps it scans on."
    )

    @field_validator("compute_delay", mode="before")
    @classmethod
    def _fixed_delay(cls, value: Any) -> Any:
        """An integer ``d`` stands for ``{min: d, max: d}``."""
        if isinstance(value, int) and not isinstance(value, bool):
            return {"min": value, "max": value}
        return value

    @model_validator(mode="after")
    def _phase_within(self) -> ClockSpec:
        if self.phase >= self.act_every:
            raise ValueError(
                f"phase {self.phase} is not below act_every {self.act_every}: step t acts when"
                f" t % act_every == phase, so phase is 0 to {self.act_every - 1}"
            )
        return self

    @property
    def varies(self) -> bool:
        """Whether its compute delay is drawn (min < max)."""
        return self.compute_delay.min < self.compute_delay.max
