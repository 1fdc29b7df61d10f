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

A study file is untrusted input: its ``name`` names the sweep folder, so it follows the
scenario's name rule (it cannot leave ``sweeps/``); its numbers are numbers (no ``true``,
no ``'20'``); and the runs it makes are counted from the axes alone, before anything is
built, so a study of a billion runs is refused at once (:data:`MAX_RUNS`). Two arms that
would be the same run (a value given twice) are refused too, and so is a ``reference``
that names no axis or no value of its axis.
"""

from __future__ import annotations

import difflib
import json
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, Literal

from pydantic import (
    Field,
    StrictFloat,
    StrictInt,
    ValidationError,
    field_validator,
    model_validator,
)

from mresim_phys.errors import ScenarioError
from mresim_phys.scenario.load import describe_errors
from mresim_phys.scenario.readers import read_yaml_mapping
from mresim_phys.scenario.schema import NAME_RULE, Name
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

    name: Name = Field(description=f"The study's name (the sweep folder's default): {NAME_RULE}.")
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
    seeds: StrictInt | list[StrictInt] = Field(
        20, description="How many seeds (0..n-1), or a list of seeds."
    )
    steps: StrictInt | None = Field(
        None, ge=1, description="Step cap for every run (null: each base's)."
    )
    overrides: dict[str, Any] = Field(
        default_factory=dict, description="Fixed overrides for every run (dotted paths allowed)."
    )
    failure_window: tuple[StrictFloat, StrictFloat] = Field(
        (0.05, 0.35),
        description="Failures (the 'failures' axis) happen uniformly between these fractions"
        " of the step cap.",
    )
    reference: dict[str, Any] = Field(
        default_factory=dict,
        description="The reference arm for paired comparisons, by axis value (default: first).",
    )

    @field_validator("axes", "reference", mode="before")
    @classmethod
    def _flatten(cls, value: Any) -> Any:
        return flatten_axes(value) if isinstance(value, Mapping) else value

    @field_validator("seeds", mode="before")
    @classmethod
    def _whole_seeds(cls, value: Any) -> Any:
        items = value if isinstance(value, list) else [value]
        if not all(type(s) is int for s in items):
            raise ValueError(
                "give a number of seeds (seeds: 20) or a list of whole numbers (seeds: [0, 5]),"
                " not true/false, text or fractions"
            )
        return value

    @field_validator("seeds")
    @classmethod
    def _seeds(cls, value: int | list[int]) -> int | list[int]:
        if value == [] or (isinstance(value, int) and value < 1):
            raise ValueError("give at least one seed")
        if isinstance(value, list) and min(value) < 0:  # a count is never built into a range
            raise ValueError("seeds are whole numbers >= 0")
        if isinstance(value, list) and repeated(value):
            raise ValueError(f"the seeds repeat: {repeated(value)}")
        return value

    @field_validator("scenarios")
    @classmethod
    def _scenarios(cls, value: list[str]) -> list[str]:
        if repeated(value):
            twice = repeated(value)
            raise ValueError(f"{twice} listed more than once would run the same arms twice")
        return value

    @model_validator(mode="after")
    def _axes(self) -> Study:
        for path, values in self.axes.items():
            check_axis(path, values)
        lengths = {len(v) for v in self.axes.values()}
        if self.mode == "zip" and len(lengths) > 1:
            shown = {p: len(v) for p, v in self.axes.items()}
            raise ValueError(f"mode zip needs axes of one length, got {shown}")
        check_arms(self.axes, self.mode)
        check_reference(self.reference, self.axes)
        low, high = self.failure_window
        if not 0 <= low < high <= 1:
            raise ValueError(f"failure_window must be 0 <= low < high <= 1, got {[low, high]}")
        check_run_count(self)
        return self

    @property
    def arm_count(self) -> int:
        """Arms: base scenarios x axis value combinations (counted, nothing built)."""
        columns = [len(v) for v in self.axes.values()]
        combos = math.prod(columns) if self.mode == "grid" else max(columns, default=1)
        return len(self.scenarios) * combos

    @property
    def seed_count(self) -> int:
        """How many seeds each arm runs."""
        return self.seeds if isinstance(self.seeds, int) else len(self.seeds)

    @property
    def run_count(self) -> int:
        """Runs: arms x seeds, counted from the study alone."""
        return self.arm_count * self.seed_count

    @property
    def seed_list(self) -> list[int]:
        """The seeds, in order."""
        return list(range(self.seeds)) if isinstance(self.seeds, int) else list(self.seeds)


def key(value: Any) -> str:
    """A value as comparable text (axis values may be lists or mappings)."""
    return json.dumps(value, sort_keys=True, default=str)


def repeated(values: Sequence[Any]) -> list[Any]:
    """The values given more than once, each once, in order.

    >>> repeated(["frontier", "random_walk", "frontier"])
    ['frontier']
    """
    seen: set[str] = set()
    found: dict[str, Any] = {}
    for value in values:
        text = key(value)
        if text in seen:
            found.setdefault(text, value)
        seen.add(text)
    return list(found.values())


def check_axis(path: str, values: list[Any]) -> None:
    """ValueError if the axis has no values, or ``failures`` holds anything but counts."""
    if not values:
        raise ValueError(f"axes.{path}: the axis has no values")
    if path == FAILURES and not all(type(k) is int and k >= 0 for k in values):
        raise ValueError(
            f"axes.failures: takes robot counts, whole numbers >= 0 (not true/false or"
            f" text), got {values}"
        )


def check_arms(axes: Mapping[str, list[Any]], mode: str) -> None:
    """ValueError if two arms would be the same: a value repeated on a grid axis, a row
    repeated in zip mode."""
    if mode == "grid":
        for path, values in axes.items():
            if repeated(values):
                raise ValueError(
                    f"axes.{path}: gives {repeated(values)} more than once, which would run"
                    " the same arms twice; give each value once"
                )
        return
    rows = [list(row) for row in zip(*axes.values(), strict=True)]
    if repeated(rows):
        shown = dict(zip(axes, repeated(rows)[0], strict=True))
        raise ValueError(
            f"axes (mode zip): the combination {shown} comes more than once, which would run"
            " the same arm twice; give each combination once"
        )


def check_reference(reference: Mapping[str, Any], axes: Mapping[str, list[Any]]) -> None:
    """ValueError if the reference names a path that is no axis or a value not swept."""
    for path, value in reference.items():
        if path not in axes:
            close = difflib.get_close_matches(path, list(axes), n=1)
            hint = f"did you mean {close[0]!r}?" if close else f"the axes: {list(axes)}"
            raise ValueError(f"reference.{path}: not an axis of the study; {hint}")
        if key(value) not in {key(v) for v in axes[path]}:
            raise ValueError(
                f"reference.{path}: {value!r} is not one of the axis's values {axes[path]}"
            )


def check_run_count(study: Study) -> None:
    """ValueError if the study makes more than :data:`MAX_RUNS` runs (counted, not built)."""
    if study.run_count > MAX_RUNS:
        raise ValueError(
            f"scenarios x axes x seeds: the study makes {study.run_count} runs"
            f" ({len(study.scenarios)} scenario(s) x {study.arm_count // len(study.scenarios)}"
            f" axis combination(s) x {study.seed_count} seed(s)), more than the {MAX_RUNS} a"
            " sweep may hold; give fewer seeds, axis values or scenarios, or split the study"
        )


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
