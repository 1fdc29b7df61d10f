"""Study files (sweeps, input): the YAML that says which runs a sweep makes, validated.

A study names one or more base scenarios (paths relative to the study file), axes over
scenario fields by dotted path (``team.strategy: [frontier, role_based]``; a nested
mapping such as ``robots: {count: [4, 8, 16]}`` is the same as ``robots.count``), the
special axis ``failures`` (k robots fail at random steps drawn per seed,
``sweeps/failures.py``), how axes combine (``mode: grid`` = every combination,
``zip`` = the i-th value of every axis together), the seeds (``seeds: 20`` = 0..19, or a
list), fixed ``overrides`` for every run and an optional step cap. Every arm (one base
scenario with one combination of axis values) is checked against the scenario schema
before anything runs (``sweeps/expand.py``).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any, Literal

from pydantic import Field, ValidationError, field_validator, model_validator

from mresim_phys.errors import ScenarioError
from mresim_phys.scenario.load import describe_errors
from mresim_phys.scenario.readers import read_yaml_mapping
from mresim_phys.strict import Strict

FAILURES = "failures"  # the axis of k random robot failures per seed
MAX_RUNS = 100_000


class StudyError(ScenarioError):
    """A study file (or a sweep folder) that cannot be used; the message names it."""


def flatten_axes(axes: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """Nested axis mappings as dotted paths.

    >>> flatten_axes({"robots": {"count": [4, 8]}, "team.speed": [3]})
    {'robots.count': [4, 8], 'team.speed': [3]}
    """
    flat: dict[str, Any] = {}
    for key, value in axes.items():
        path = f"{prefix}{key}"
        if isinstance(value, Mapping):
            flat |= flatten_axes(value, f"{path}.")
        else:
            flat[path] = value
    return flat


class Study(Strict):
    """A sweep: base scenarios x axes x seeds."""

    name: str = Field(min_length=1, description="The study's name (the sweep folder's default).")
    scenarios: list[str] = Field(
        min_length=1, description="Base scenario files, relative to the study file."
    )
    axes: dict[str, list[Any]] = Field(
        default_factory=dict,
        description="Scenario fields by dotted path -> the values to sweep (null: switched off).",
    )
    mode: Literal["grid", "zip"] = Field(
        "grid", description="grid: every combination of the axes; zip: the i-th values together."
    )
    seeds: int | list[int] = Field(20, description="How many seeds (0..n-1), or a list of seeds.")
    steps: int | None = Field(None, ge=1, description="Step cap for every run (null: each base's).")
    overrides: dict[str, Any] = Field(
        default_factory=dict, description="Fixed overrides for every run (dotted paths allowed)."
    )
    failure_window: tuple[float, float] = Field(
        (0.05, 0.35),
        description="Failures (the 'failures' axis) happen uniformly between these fractions"
        " of the step cap.",
    )
    reference: dict[str, Any] = Field(
        default_factory=dict,
        description="The reference arm for paired comparisons, by axis value (default: first).",
    )

    @field_validator("axes", mode="before")
    @classmethod
    def _flatten(cls, value: Any) -> Any:
        return flatten_axes(value) if isinstance(value, Mapping) else value

    @field_validator("seeds")
    @classmethod
    def _seeds(cls, value: int | list[int]) -> int | list[int]:
        seeds = range(value) if isinstance(value, int) else value
        if not seeds:
            raise ValueError("give at least one seed")
        if isinstance(value, list) and len(set(value)) != len(value):
            raise ValueError(f"the seeds repeat: {value}")
        if min(seeds) < 0:
            raise ValueError("seeds are whole numbers >= 0")
        return value

    @model_validator(mode="after")
    def _axes(self) -> Study:
        for path, values in self.axes.items():
            if not values:
                raise ValueError(f"axis {path!r} has no values")
            if path == FAILURES and not all(isinstance(k, int) and k >= 0 for k in values):
                raise ValueError(f"axis 'failures' takes robot counts >= 0, got {values}")
        lengths = {len(v) for v in self.axes.values()}
        if self.mode == "zip" and len(lengths) > 1:
            shown = {p: len(v) for p, v in self.axes.items()}
            raise ValueError(f"mode zip needs axes of one length, got {shown}")
        low, high = self.failure_window
        if not 0 <= low < high <= 1:
            raise ValueError(f"failure_window must be 0 <= low < high <= 1, got {[low, high]}")
        return self

    @property
    def seed_list(self) -> list[int]:
        """The seeds, in order."""
        return list(range(self.seeds)) if isinstance(self.seeds, int) else list(self.seeds)


def parse_study(data: Mapping[str, Any], source: str) -> Study:
    """``data`` validated as a study; StudyError naming ``source`` and the field."""
    try:
        return Study.model_validate(data)
    except ValidationError as exc:
        text = describe_errors(source, exc, keys=list(Study.model_fields))
        raise StudyError(text.replace("in the scenario", "in the study")) from None


def load_study(path: Path) -> Study:
    """The study file at ``path``, validated (scenario paths stay relative to its folder)."""
    try:
        data = read_yaml_mapping(Path(path))
    except ScenarioError as exc:  # the reader's messages speak of a scenario file
        raise StudyError(str(exc).replace("Scenario file", "Study file", 1)) from None
    return parse_study(data, str(path))
