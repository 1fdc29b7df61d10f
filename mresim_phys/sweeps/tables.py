"""Sweep tables (sweeps, output edge): ``runs.parquet`` and ``steps.parquet``, with pyarrow.

``runs.parquet`` has one row per run, failed runs included: ``run_id``, ``arm``,
``label``, ``scenario``, one column per axis (named by its path, e.g. ``team.strategy``),
``seed``, ``status`` (done, failed or lost), ``error`` and ``log`` (failed and lost runs),
``run_time_s`` (the worker's wall time), ``attempt`` (1, or more for a run run again after
a lost or failed attempt), then the run's summary figures (``summary.json`` flattened:
``steps_to_explored_90`` for ``steps_to_explored["0.9"]``, the ``communication`` block's
fields, ``failed_robots`` (the summary's ``failures``, counted), the robustness figures,
the run-health totals ``robots_idle_with_frontier``, ``idle_robot_steps``,
``stuck_robot_steps``, ``waiting_robot_steps``, ``robots_fruitless`` and
``fruitless_robot_steps``) and, for paired runs,
``robustness.json``'s differences (``diff_<name>``). Wall-clock columns are
:data:`WALL_COLUMNS`; everything else is the same on any machine and any backend.

``steps.parquet`` is the long table: ``run_id``, then every ``metrics.csv`` column
(per-robot columns of robots a run does not have are null).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from mresim_phys.knowledge.health import TOTALS
from mresim_phys.meeting_board import REASONS
from mresim_phys.output.files import atomic_path
from mresim_phys.sweeps.expand import RunSpec
from mresim_phys.sweeps.worker import DONE, run_folder

RUNS_TABLE = "runs.parquet"
STEPS_TABLE = "steps.parquet"
WALL_COLUMNS = ("run_time_s", "wall_time_s", "steps_per_second")
SKIPPED = ("name", "seed", "robots")


def threshold_key(text: str) -> str:
    """``"0.9"`` -> ``"90"``.

    >>> threshold_key("0.95")
    '95'
    """
    return str(round(float(text) * 100))


def flatten_summary(summary: dict[str, Any]) -> dict[str, Any]:
    """summary.json's figures as flat columns."""
    row: dict[str, Any] = {}
    for key, value in summary.items():
        if key in SKIPPED:
            continue
        if key.startswith("steps_to_") and isinstance(value, dict):
            row |= {f"{key}_{threshold_key(t)}": v for t, v in value.items()}
        elif key == "communication" and isinstance(value, dict):
            row |= value
        elif key == "failures" and isinstance(value, list):
            row["failed_robots"] = len(value)
        elif key == "health" and isinstance(value, dict):
            row |= {name: value.get(name) for name in TOTALS}
        elif key == "localization" and isinstance(value, dict):
            row |= localization_columns(value)
        elif key == "meetings" and isinstance(value, dict):
            row |= meeting_columns(value)
        elif key == "team" and isinstance(value, dict):  # metrics.team (output/team.py)
            row |= {k: value.get(k) for k in ("overlap", "workload_cv", "longest_path")}
        elif not isinstance(value, (dict, list)):
            row[key] = value
    return row


def localization_columns(block: dict[str, Any]) -> dict[str, Any]:
    """summary.json's ``localization`` object as columns: the team's pose errors, the base
    map's consistency and the robots' mean consistency."""
    team, base, robots = block["team"], block["base"], list(block["robots"].values())
    return {
        "pose_error_final_mean": team["final_mean_error"],
        "pose_error_max": team["max_error"],
        "pose_error_mean": team["mean_error"],
        "base_false_free": base["false_free"],
        "base_false_occupied": base["false_occupied"],
        "robots_false_free": sum(r["false_free"] for r in robots) / len(robots),
        "robots_false_occupied": sum(r["false_occupied"] for r in robots) / len(robots),
    }


def meeting_columns(block: dict[str, Any]) -> dict[str, Any]:
    """summary.json's ``meetings`` object as columns: kept, missed (and per reason),
    superseded, the keep rate and the mean waiting time (docs/rendezvous.md)."""
    missed = block["missed"]
    return {
        "meetings_planned": block["planned"],
        "meetings_kept": block["kept"],
        "meetings_missed": missed["total"],
        **{f"meetings_missed_{reason}": missed[reason] for reason in REASONS},
        "meetings_superseded": block["superseded"],
        "meeting_keep_rate": block["keep_rate"],
        "meeting_wait_mean": block["waiting"]["mean"],
    }


def robustness_row(folder: Path) -> dict[str, Any]:
    """A paired run's differences against its fault-free baseline (robustness.json)."""
    path = folder / "robustness.json"
    if not path.is_file():
        return {}
    report = json.loads(path.read_text(encoding="utf-8"))
    return {f"diff_{k}": v for k, v in report.get("difference", {}).items()}


def run_row(sweep: Path, spec: RunSpec, record: dict[str, Any]) -> dict[str, Any]:
    """One row of runs.parquet."""
    row: dict[str, Any] = {
        "run_id": spec.run_id,
        "arm": spec.arm,
        "label": spec.label,
        "scenario": spec.scenario,
    }
    row |= {path: cell(value) for path, value in spec.values.items()}
    row |= {
        "seed": spec.seed,
        "status": record["status"],
        "error": record.get("error"),
        "log": record.get("log"),
        "run_time_s": record.get("run_time_s"),
        "attempt": record.get("attempt", 1),
    }
    folder = run_folder(sweep, spec.run_id)
    if record["status"] == DONE:
        summary = json.loads((folder / "summary.json").read_text(encoding="utf-8"))
        row |= flatten_summary(summary) | robustness_row(folder)
    return row


def cell(value: Any) -> Any:
    """An axis value as a table cell (lists and mappings as their JSON text)."""
    return json.dumps(value) if isinstance(value, (list, dict)) else value


def write_table(frame: pd.DataFrame, path: Path) -> Path:
    """``frame`` as a parquet file at ``path``, atomically; columns of mixed types as text."""
    for column in frame.columns:
        kinds = {type(v) for v in frame[column] if v is not None and v == v}
        if len(kinds - {int, float}) and len(kinds) > 1:
            frame[column] = [None if v is None or v != v else str(v) for v in frame[column]]
    table = pa.Table.from_pandas(frame, preserve_index=False)
    with atomic_path(path) as tmp:
        pq.write_table(table, tmp)
    return path


def write_runs(sweep: Path, specs: list[RunSpec], records: dict[str, dict[str, Any]]) -> Path:
    """runs.parquet of every finished run, in run order."""
    rows = [run_row(sweep, s, records[s.run_id]) for s in specs if s.run_id in records]
    return write_table(pd.DataFrame(rows), Path(sweep) / RUNS_TABLE)


def write_steps(sweep: Path, specs: list[RunSpec], records: dict[str, dict[str, Any]]) -> Path:
    """steps.parquet: every done run's metrics.csv with its run id."""
    frames = []
    for spec in specs:
        if records.get(spec.run_id, {}).get("status") != DONE:
            continue
        frame = pd.read_csv(run_folder(sweep, spec.run_id) / "metrics.csv")
        frame.insert(0, "run_id", spec.run_id)
        frames.append(frame)
    table = pd.concat(frames, ignore_index=True) if frames else pd.DataFrame({"run_id": []})
    return write_table(table, Path(sweep) / STEPS_TABLE)
