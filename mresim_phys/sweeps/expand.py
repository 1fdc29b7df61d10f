"""Study expansion (sweeps, input): a study -> its arms, checked, -> one run per arm and seed.

An arm is one base scenario with one combination of axis values (``grid``: every
combination, ``zip``: the i-th values together; the base scenarios are always crossed
with the combinations). Every arm is applied to its scenario's YAML data and validated by
the scenario schema before anything runs, so an unknown path (with a close match) or a
value the schema rejects is reported with the arm that holds it; so is what only the map
shows (a start or the base inside a wall), as each arm's world is built once. A run is an
arm with a seed: its complete scenario data (seed, failures of that seed, the sweep's render
settings: no plots, no video unless asked; one thread per run, as the workers are the
parallelism; threads never change results), ready for any worker process or Dask worker.
"""

from __future__ import annotations

import hashlib
import itertools
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mresim_phys.build import build_setup
from mresim_phys.errors import MresimError
from mresim_phys.scenario.load import (
    check_own_values,
    resolve_map_path,
    resolve_mask_paths,
    validate_scenario,
)
from mresim_phys.scenario.overrides import apply_overrides
from mresim_phys.scenario.readers import read_yaml_mapping
from mresim_phys.scenario.schema import Scenario
from mresim_phys.sweeps.axes import COUNT, apply_axis, shown
from mresim_phys.sweeps.failures import with_failures
from mresim_phys.sweeps.placement import resize_team
from mresim_phys.sweeps.study import FAILURES, Study, StudyError, flatten_axes

SWEEP_RENDER = {"plots": False, "video": False}  # a sweep's runs: metrics, summary, run log


@dataclass(frozen=True)
class Arm:
    """One base scenario with one combination of axis values, validated."""

    index: int
    source: str  # the base scenario file
    values: dict[str, Any]
    data: dict[str, Any]  # YAML data with the axes applied (failures excepted)
    scenario: Scenario

    @property
    def label(self) -> str:
        """``scenario-name: path=value, ...``."""
        return f"{self.scenario.name}: {shown(self.values)}" if self.values else self.scenario.name


@dataclass(frozen=True)
class RunSpec:
    """One run of a sweep: everything a worker needs (picklable plain data)."""

    run_id: str
    arm: int
    label: str
    scenario: str  # the base scenario's name
    source: str  # the base scenario file (relative map paths are relative to it)
    values: dict[str, Any]
    seed: int
    data: dict[str, Any] = field(repr=False)
    video: str | None = None  # a video path when --video-for selects the run

    def load(self) -> Scenario:
        """The run's scenario, validated, its paths resolved."""
        scenario = validate_scenario(self.data, self.source)
        folder = Path(self.source).resolve().parent
        located = resolve_map_path(scenario, folder, self.source)
        return resolve_mask_paths(located, folder, self.source)


def combinations(study: Study) -> list[dict[str, Any]]:
    """The axis value combinations, in order (one empty combination without axes)."""
    paths = list(study.axes)
    if not paths:
        return [{}]
    columns = [study.axes[p] for p in paths]
    rows = itertools.product(*columns) if study.mode == "grid" else zip(*columns, strict=True)
    return [dict(zip(paths, row, strict=True)) for row in rows]


def base_data(study: Study, path: Path, study_path: Path) -> dict[str, Any]:
    """A base scenario's YAML data with the study's fixed overrides and step cap (the file's
    own values checked first: an override replaces a wrong value, it does not excuse it)."""
    try:
        data = read_yaml_mapping(path)
        check_own_values(data, str(path))
    except MresimError as exc:
        raise StudyError(f"{study_path}: scenarios: {exc}") from None
    fixed = {"simulation.threads": 1, **flatten_axes(study.overrides)}  # one core per run
    if study.steps is not None:
        fixed["steps"] = study.steps
    try:
        for key, value in fixed.items():
            data = apply_axis(data, key, value, str(path))
    except MresimError as exc:
        raise StudyError(f"{study_path}: overrides: {exc}") from None
    return apply_overrides(data, {"render": SWEEP_RENDER}, str(path))


def make_arm(index: int, path: Path, base: dict[str, Any], values: dict[str, Any]) -> Arm:
    """Apply ``values`` to ``base`` and validate (MresimError from the schema)."""
    source = str(path)
    data = base
    for axis, value in values.items():
        if axis not in (COUNT, FAILURES):
            data = apply_axis(data, axis, value, source)
    scenario = validate_scenario(data, source)
    folder = path.resolve().parent
    if COUNT in values:
        located = resolve_map_path(scenario, folder, source)
        data = resize_team(data, located, values[COUNT], source)
        scenario = validate_scenario(data, source)
    # what the schema cannot see (the map, a start or the base inside a wall, events off
    # the map): the arm's world is built once, as `mresim validate` does (~10-50 ms)
    build_setup(resolve_mask_paths(resolve_map_path(scenario, folder, source), folder, source))
    return Arm(index, source, values, data, scenario)


def expand_arms(study: Study, study_path: Path) -> list[Arm]:
    """Every arm of the study, validated; StudyError naming the arm of the first problem."""
    folder = Path(study_path).resolve().parent
    arms: list[Arm] = []
    for file in study.scenarios:
        path = folder / file
        base = base_data(study, path, study_path)
        for values in combinations(study):
            try:
                arms.append(make_arm(len(arms), path, base, values))
            except MresimError as exc:
                where = f"arm {len(arms)} ({file}: {shown(values) or 'no axes'})"
                raise StudyError(f"{study_path}: {where}: {exc}") from None
    return arms


def run_id(arm: int, seed: int) -> str:
    """A run's folder name: ``a<arm>-s<seed>``.

    >>> run_id(3, 12)
    'a003-s0012'
    """
    return f"a{arm:03d}-s{seed:04d}"


def expand_runs(study: Study, study_path: Path) -> list[RunSpec]:
    """Every run of the study: arms x seeds, arm by arm; checked before anything runs (the
    study itself holds at most ``MAX_RUNS`` runs: they were counted when it was read)."""
    arms = expand_arms(study, study_path)
    return [make_run(study, arm, seed, study_path) for arm in arms for seed in study.seed_list]


def make_run(study: Study, arm: Arm, seed: int, study_path: Path) -> RunSpec:
    """The run of ``arm`` with ``seed`` (and that seed's failures)."""
    data = dict(arm.data, seed=seed)
    if FAILURES in arm.values:
        names = [r.name for r in arm.scenario.robots]
        where = f"{study_path}: arm {arm.index} ({shown(arm.values)})"
        k, steps = arm.values[FAILURES], arm.scenario.steps
        data = with_failures(data, names, k, seed, steps, study.failure_window, where)
    return RunSpec(
        run_id(arm.index, seed),
        arm.index,
        arm.label,
        arm.scenario.name,
        arm.source,
        dict(arm.values),
        seed,
        data,
    )


def fingerprints(runs: list[RunSpec]) -> dict[str, str]:
    """Each run's id -> a hash of its scenario data (equal data, equal hash)."""
    return {r.run_id: data_hash(r.data) for r in runs}


def data_hash(data: dict[str, Any]) -> str:
    """A short hash of scenario data."""
    text = json.dumps(data, sort_keys=True, default=str)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]
