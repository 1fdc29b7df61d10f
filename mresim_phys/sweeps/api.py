"""The Python sweep API (sweeps): run a study from Python and get its tables as pandas
DataFrames, as ``mesa.batch_run`` does.

``run_study(study, out=..., workers=...)`` takes a study file or a study as a mapping (the
same keys as a study file, docs/sweeps.md; a mapping's relative scenario paths are to
``base``, default the working folder), runs every run missing from ``out`` as ``mresim
sweep`` does (the same folder, manifest and lock: a run already done is not run again), and
returns the runs table (``runs.parquet``: one row per run, its axis values, status and
metrics); with ``steps=True`` also the steps table (``steps.parquet``). A failed run is a
row with ``status`` ``failed``, never an average; a mistake in the study raises
``StudyError`` naming the field.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import pandas as pd
import yaml

from mresim_phys.sweeps.runner import SweepOptions, run_sweep
from mresim_phys.sweeps.study import load_study, parse_study


def run_study(
    study: str | Path | Mapping[str, Any],
    *,
    out: str | Path | None = None,
    workers: int | None = None,
    dask: str | None = None,
    steps: bool = False,
    retry_failed: bool = False,
    quiet: bool = True,
    base: str | Path | None = None,
) -> pd.DataFrame | tuple[pd.DataFrame, pd.DataFrame]:
    """Run ``study`` into ``out`` (default ``sweeps/<name>``) on ``workers`` local
    processes (default: the cores) or the Dask scheduler ``dask``; the runs table, and the
    steps table too with ``steps`` (module docstring)."""
    if isinstance(study, Mapping):
        folder = Path(base) if base is not None else Path.cwd()
        data = with_absolute_scenarios(dict(study), folder)
        path = folder / "<study>"
        parsed = parse_study(data, "run_study")
        text = yaml.safe_dump(data, sort_keys=False)
    else:
        path = Path(study)
        parsed = load_study(path)
        text = path.read_text(encoding="utf-8")
    folder_out = Path(out) if out is not None else Path("sweeps") / parsed.name
    options = SweepOptions(folder_out, workers, dask, None, False, quiet, retry_failed=retry_failed)
    result = run_sweep(parsed, path, text, options)
    if not quiet:
        print(result.summary())
    runs = pd.read_parquet(result.folder / "runs.parquet")
    if not steps:
        return runs
    return runs, pd.read_parquet(result.folder / "steps.parquet")


def with_absolute_scenarios(data: dict[str, Any], folder: Path) -> dict[str, Any]:
    """``data`` with its scenario paths made absolute from ``folder``."""
    scenarios = data.get("scenarios")
    if isinstance(scenarios, list):
        data["scenarios"] = [
            str(p if Path(str(p)).is_absolute() else (folder / str(p)).resolve()) for p in scenarios
        ]
    return data
