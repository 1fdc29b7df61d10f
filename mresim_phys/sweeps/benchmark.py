"""Benchmarks (sweeps, output edge): ``mresim benchmark SUITE`` and ``--check RESULTS``.

A suite file fixes everything a results table depends on::

    name: small
    instances: instances_small.yaml   # a set file (mapgen/sets.py), relative to the suite
    split: test                       # which of its instances: all, train or test
    strategies: [frontier, nearest_frontier, voronoi]
    team_sizes: [4]                   # robots per run (robots.count)
    failures: [0, 1]                  # robots that fail at random per run
    seeds: 2
    steps: 600
    metrics: {levels: [0.85, 0.99], budget: {explored: 0.9, within: 600}, team: true}

``mresim benchmark SUITE --out DIR`` draws the set into ``DIR/instances`` (the maps'
SHA-256 checked against its index), builds the study of the chosen instances x strategies x
team sizes x failures x seeds (``DIR/study.yaml``), runs it on the sweep machinery (local
pool or Dask, resumable: ``DIR/sweep``) and writes:

* ``DIR/results.parquet`` and ``DIR/results.md``: one row per run; per kind and strategy
  (and team size, failures) the runs, the success rate within the budget, the Kaplan-Meier
  median of the steps to 90 % explored (censored runs never averaged) and the mean overlap,
  workload balance and longest path;
* ``DIR/results.json``: the suite's SHA-256, the package versions, each instance's grid
  SHA-256, each run's scenario and ``metrics.csv`` SHA-256.

``mresim benchmark --check DIR [--sample N]`` re-runs N runs of it (a seeded choice; all
with ``--sample 0``) from their scenarios and confirms each ``metrics.csv`` byte for byte
against ``results.json`` (and that the run folders still hold what it records): exit 1
with the runs that differ.
"""

from __future__ import annotations

import hashlib
import importlib
import json
import platform
import subprocess
import sys
import tempfile
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any, Literal

import numpy as np
import pandas as pd
import yaml
from pydantic import Field, ValidationError

from mresim_phys.errors import MresimError
from mresim_phys.mapgen.errors import describe
from mresim_phys.mapgen.sets import SetSpec, make_set
from mresim_phys.rng import Streams
from mresim_phys.scenario.yamlfile import read_yaml_file
from mresim_phys.strict import Strict
from mresim_phys.sweeps.survival import censored, km_median

PACKAGES = ("mresim_phys", "numpy", "scipy", "pymunk", "shapely", "numba", "pydantic",
            "opencv-python-headless", "scikit-image", "pandas", "pyarrow")  # fmt: skip
COLUMNS = ("run_id", "instance", "kind", "team.strategy", "robots.count", "failures", "seed",
           "status", "steps", "final_explored", "final_known_at_base", "steps_to_explored_90",
           "success", "overlap", "workload_cv", "longest_path")  # fmt: skip


class SuiteSpec(Strict):
    """A benchmark suite (module docstring)."""

    name: str = Field(min_length=1, max_length=64, pattern=r"^[A-Za-z0-9_.-]+$")
    instances: str = Field(description="A set file, relative to the suite file.")
    split: Literal["all", "train", "test"] = "all"
    strategies: list[str] = Field(min_length=1)
    team_sizes: list[int] = Field(default_factory=lambda: [4], min_length=1)
    failures: list[int] = Field(default_factory=lambda: [0], min_length=1)
    seeds: int = Field(2, ge=1, le=1000)
    steps: int = Field(600, ge=1, le=1_000_000)
    metrics: dict[str, Any] = Field(default_factory=lambda: {"team": True})


def sha256_of(path: Path) -> str:
    """SHA-256 of a file's bytes."""
    return hashlib.sha256(path.read_bytes()).hexdigest()


def load_suite(path: Path) -> tuple[SuiteSpec, SetSpec, str, Path]:
    """The suite, its set, the suite's text and the set file (MresimError naming the file
    and field)."""
    data = read_yaml_file(path, "Suite file", MresimError)
    try:
        suite = SuiteSpec.model_validate(data)
    except ValidationError as exc:
        raise MresimError(f"{path}: {describe(exc)}") from None
    set_path = (path.parent / suite.instances).resolve()
    set_data = read_yaml_file(set_path, "Set file", MresimError)
    try:
        instances = SetSpec.model_validate(set_data)
    except ValidationError as exc:
        raise MresimError(f"{set_path}: {describe(exc)}") from None
    return suite, instances, path.read_text(encoding="utf-8"), set_path


def study_of(suite: SuiteSpec, index: dict[str, Any], folder: Path) -> dict[str, Any]:
    """The study of the suite's chosen instances (module docstring)."""
    chosen = [i for i in index["instances"] if suite.split in ("all", i["split"])]
    if not chosen:
        raise MresimError(f"suite {suite.name}: its set has no {suite.split} instance")
    axes: dict[str, Any] = {
        "team.strategy": suite.strategies,
        "robots": {"count": suite.team_sizes},
    }
    if suite.failures != [0]:
        axes["failures"] = suite.failures
    metrics = {f"metrics.{k}": v for k, v in suite.metrics.items()}
    return {
        "name": suite.name,
        "scenarios": [str(folder / "instances" / i["id"] / "scenario.yaml") for i in chosen],
        "axes": axes,
        "seeds": suite.seeds,
        "steps": suite.steps,
        "overrides": {"stop.explored": 0.99, **metrics},
    }


def run_benchmark(suite_path: Path, out: Path, sweep_flags: Any) -> int:
    """Draw, sweep and tabulate a suite (module docstring); 1 if runs failed."""
    from mresim_phys.sweeps.runner import SweepOptions, run_sweep
    from mresim_phys.sweeps.study import parse_study

    suite, instances, text, set_path = load_suite(suite_path)
    try:
        index = make_set(instances, out / "instances", set_path)
    except ValueError as exc:
        raise MresimError(f"{suite_path}: {exc}") from None
    data = study_of(suite, index, out.resolve())
    study_path = out / "study.yaml"
    study_text = yaml.safe_dump(data, sort_keys=False)
    study_path.write_text(study_text, encoding="utf-8")
    study = parse_study(data, str(study_path))
    f = sweep_flags
    options = SweepOptions(
        out / "sweep", f.workers, f.dask, None, f.verbose, f.quiet, retry_failed=f.retry_failed
    )
    result = run_sweep(study, study_path, study_text, options)
    if not f.quiet:
        print(result.summary())
    write_results(out, suite, index, text)
    return 0 if result.complete else 1


def results_table(out: Path, index: dict[str, Any]) -> pd.DataFrame:
    """One row per run: its instance and kind, the axes, the figures (module docstring)."""
    runs = pd.read_parquet(out / "sweep" / "runs.parquet")
    kinds = {i["id"]: i["kind"] for i in index["instances"]}
    runs["instance"] = runs["scenario"]  # each instance's scenario is named by its id
    runs["kind"] = runs["instance"].map(kinds)
    for name in COLUMNS:
        if name not in runs:
            runs[name] = None
    table: pd.DataFrame = runs[list(COLUMNS)].copy()
    return table


def write_results(out: Path, suite: SuiteSpec, index: dict[str, Any], text: str) -> None:
    """results.parquet, results.md and results.json."""
    table = results_table(out, index)
    table.to_parquet(out / "results.parquet", index=False)
    (out / "results.md").write_text(markdown(suite, table), encoding="utf-8")
    sweep = out / "sweep" / "runs"
    runs = {}
    for run_id in table["run_id"]:
        folder = sweep / str(run_id)
        if (folder / "metrics.csv").is_file():
            runs[str(run_id)] = {
                "scenario_sha256": sha256_of(folder / "scenario.yaml"),
                "metrics_sha256": sha256_of(folder / "metrics.csv"),
            }
    record = {
        "suite": suite.name,
        "suite_sha256": hashlib.sha256(text.encode("utf-8")).hexdigest(),
        "python": platform.python_version(),
        "processor": processor(),
        "packages": {name: package_version(name) for name in PACKAGES},
        "instances": {i["id"]: i["grid_sha256"] for i in index["instances"]},
        "runs": runs,
    }
    (out / "results.json").write_text(json.dumps(record, indent=2) + "\n", encoding="utf-8")


def processor() -> dict[str, Any]:
    """This machine's architecture and the vector extensions numpy found on it: another
    processor may round a library routine's last bit otherwise (docs/seeds.md)."""
    try:  # numpy's own (not public) table; the architecture alone if it moved
        umath = importlib.import_module("numpy._core._multiarray_umath")
        features: dict[str, bool] = dict(getattr(umath, "__cpu_features__", {}))
    except ImportError:
        features = {}
    return {"machine": platform.machine(), "simd": sorted(k for k, v in features.items() if v)}


def package_version(name: str) -> str:
    """The installed version of a package ('unknown' without its metadata)."""
    try:
        return version(name)
    except PackageNotFoundError:
        return "unknown"


def markdown(suite: SuiteSpec, table: pd.DataFrame) -> str:
    """The results table per kind, strategy, team size and failures (module docstring)."""
    lines = [
        f"# Benchmark {suite.name}",
        "",
        f"{len(table)} runs: {suite.split} instances, {suite.seeds} seeds, {suite.steps} steps.",
        "Steps to 90 % explored: Kaplan-Meier median [95 % interval], runs that never got"
        " there censored (never averaged).",
        "",
        "| kind | strategy | robots | failures | runs | success | steps to 90 % | not reached"
        " | overlap | workload cv | longest path |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    done = table[table["status"] == "done"].copy()
    done["steps_to_explored_90"] = pd.to_numeric(done["steps_to_explored_90"], errors="coerce")
    keys = ["kind", "team.strategy", "robots.count", "failures"]
    for values, group in done.groupby(keys, dropna=False, sort=True):
        kind, strategy, count, failures = values
        median, low, high = km_median(censored(group, "steps_to_explored_90"))
        success = pd.to_numeric(group["success"], errors="coerce").mean()
        lines.append(
            f"| {kind} | {strategy} | {count} | {0 if pd.isna(failures) else failures}"
            f" | {len(group)} | {fmt(success, '.0%')} | {fmt(median, '.0f')}"
            f" [{fmt(low, '.0f')}, {fmt(high, '.0f')}]"
            f" | {int(group['steps_to_explored_90'].isna().sum())}"
            f" | {fmt(mean_of(group, 'overlap'), '.3f')}"
            f" | {fmt(mean_of(group, 'workload_cv'), '.2f')}"
            f" | {fmt(mean_of(group, 'longest_path'), '.0f')} |"
        )
    return "\n".join(lines) + "\n"


def mean_of(group: pd.DataFrame, name: str) -> float:
    """The mean of a column (NaN without values)."""
    values = pd.to_numeric(group[name], errors="coerce").dropna()
    return float(values.mean()) if len(values) else float("nan")


def fmt(value: Any, spec: str) -> str:
    """A number, '-' for NaN, 'not reached' for inf."""
    if value is None or (isinstance(value, float) and np.isnan(value)):
        return "-"
    if isinstance(value, float) and np.isinf(value):
        return "not reached"
    return format(value, spec)


def check_results(folder: Path, sample: int) -> list[str]:
    """Re-run ``sample`` runs of a benchmark (0: all), each in a fresh process, and
    compare (module docstring): the problems found (empty: every run confirmed)."""
    path = folder / "results.json"
    try:
        record = json.loads(path.read_text(encoding="utf-8"))
        runs: dict[str, dict[str, str]] = dict(record["runs"])
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise MresimError(f"{path}: not a benchmark's results.json ({exc})") from None
    names = sorted(runs)
    if sample:
        order = Streams(0).get("benchmark-check").permutation(len(names))[:sample]
        names = [names[i] for i in sorted(order.tolist())]
    problems = []
    with tempfile.TemporaryDirectory() as scratch:
        for name in names:
            run = folder / "sweep" / "runs" / name
            expected = runs[name]
            if not (run / "scenario.yaml").is_file():
                problems.append(f"{name}: its run folder is missing")
                continue
            if sha256_of(run / "scenario.yaml") != expected.get("scenario_sha256"):
                problems.append(f"{name}: scenario.yaml is not the one results.json records")
                continue
            if sha256_of(run / "metrics.csv") != expected.get("metrics_sha256"):
                problems.append(f"{name}: metrics.csv is not the one results.json records")
            again = Path(scratch) / name
            args = ["run", str(run / "scenario.yaml"), "--out", str(again), "--quiet", "--no-plots"]
            done = subprocess.run(
                [sys.executable, "-m", "mresim_phys.cli", *args], capture_output=True, check=False
            )
            metrics = again / "metrics.csv"
            same = metrics.is_file() and sha256_of(metrics) == expected.get("metrics_sha256")
            if done.returncode != 0 or not same:
                problems.append(f"{name}: re-run gives another metrics.csv{elsewhere(record)}")
    return problems


def elsewhere(record: dict[str, Any]) -> str:
    """A note when ``record`` was made on another kind of processor than this one."""
    recorded = record.get("processor")
    if recorded is None or recorded == processor():
        return ""
    return (
        f" (recorded on a {recorded.get('machine')} processor with other vector extensions"
        " than this one: floats may round otherwise, docs/seeds.md)"
    )
