"""A sweep folder as ``mresim compare`` reads it (sweeps, compare input): checked first.

A sweep folder is untrusted input: ``sweep.json`` may be any JSON, and ``runs.parquet`` or
``steps.parquet`` may lack columns or hold other kinds of values. :func:`read_sweep` checks
what compare uses (``sweep.json`` is an object whose ``axes`` is a list of names and whose
``reference`` is a mapping; the tables have the key columns, of numbers where numbers are
needed; the axes of ``sweep.json`` are columns of ``runs.parquet``; a step of a run appears
once), so each mistake is one message naming the file and the field (exit status 2).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from mresim_phys.errors import MresimError
from mresim_phys.sweeps.manifest import SWEEP_FILE
from mresim_phys.sweeps.shards import SHARDS, missing_shards, note_missing, shard_folders
from mresim_phys.sweeps.tables import RUNS_TABLE, STEPS_TABLE
from mresim_phys.sweeps.worker import DONE

RUNS_KEYS = ("run_id", "label", "scenario", "seed", "status", "error", "log")
STEPS_KEYS = ("run_id", "step", "explored", "known_at_base")
STEPS_NUMBERS = ("step", "explored", "known_at_base")
REWRITE = (
    " The tables are written by `mresim sweep`: run the sweep again into this folder (it"
    " runs nothing that is done and rewrites them; the folder's study.yaml is the study as"
    " last given)."
)


@dataclass
class Sweep:
    """A finished sweep's tables and record."""

    folder: Path
    runs: pd.DataFrame
    steps: pd.DataFrame
    info: dict[str, Any] = field(default_factory=dict)

    @property
    def title(self) -> str:
        """The study's name and the folder."""
        return f"{self.info.get('study', self.folder.name)} ({self.folder})"

    @property
    def axes(self) -> list[str]:
        """The swept columns (``scenario`` too when the study has several)."""
        axes = list(self.info.get("axes", []))
        return (["scenario"] if self.runs["scenario"].nunique() > 1 else []) + axes


def damaged(path: Path, what: str) -> MresimError:
    """The message for a sweep file that does not hold what compare needs."""
    return MresimError(f"{path}: {what}.{REWRITE}")


def read_sweep(folder: Path) -> Sweep:
    """The sweep in ``folder``; MresimError if it is none, or its files are damaged."""
    folder = Path(folder)
    if not (folder / SWEEP_FILE).is_file() and (folder / SHARDS).is_dir():
        return read_shards(folder)
    sweep = read_tables(folder)
    require_done(folder, sweep.runs)
    return sweep


def require_done(folder: Path, runs: pd.DataFrame) -> None:
    """A sweep compare can read has at least one finished run."""
    if not (runs["status"] == DONE).any():
        raise MresimError(f"{folder}: no run of the sweep finished; nothing to compare.")


def read_tables(folder: Path) -> Sweep:
    """The tables of one sweep folder, checked (its runs may all have failed: a shard)."""
    paths = [folder / SWEEP_FILE, folder / RUNS_TABLE, folder / STEPS_TABLE]
    missing = [p.name for p in paths if not p.is_file()]
    if missing:
        raise MresimError(
            f"{folder} is not a finished sweep folder (missing {', '.join(missing)}); give the"
            " --out folder of `mresim sweep` (re-run the sweep to finish it)."
        )
    info = read_info(paths[0])
    runs, steps = read_table(paths[1]), read_table(paths[2])
    check_runs(paths[1], runs, info)
    check_steps(paths[2], steps)
    return Sweep(folder, runs, steps, info)


def read_shards(folder: Path) -> Sweep:
    """The union of the finished shards of a sharded sweep (``sweeps/shards.py``): their
    runs and steps tables, one study; the shards missing are named on stderr."""
    done = [p for p in shard_folders(folder) if (p / RUNS_TABLE).is_file()]
    if not done:
        raise MresimError(f"{folder}: no shard of the sweep has finished; nothing to compare.")
    parts = [read_tables(p) for p in done]  # a shard whose runs all failed still counts
    names = {str(p.info.get("study")) for p in parts}
    if len(names) > 1:
        raise MresimError(f"{folder / SHARDS}: shards of different studies ({sorted(names)})")
    runs = pd.concat([p.runs for p in parts], ignore_index=True)
    repeated = runs["run_id"][runs["run_id"].duplicated()].tolist()
    if repeated:
        raise damaged(folder / SHARDS, f"runs {repeated[:3]} are in more than one shard")
    require_done(folder, runs)
    steps = pd.concat([p.steps for p in parts], ignore_index=True)
    note_missing(folder, missing_shards(done))
    info = dict(parts[0].info)
    info["runs"] = {k: v for p in parts for k, v in (p.info.get("runs") or {}).items()}
    return Sweep(folder, runs, steps, info)


def read_info(path: Path) -> dict[str, Any]:
    """``sweep.json``, checked: an object, ``axes`` a list of names, ``reference`` a mapping."""
    try:
        info = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise MresimError(f"{path}: cannot read the sweep record ({exc}).") from None
    if not isinstance(info, dict):
        raise damaged(path, f"the sweep record is {type(info).__name__}, not a JSON object")
    axes = info.get("axes", [])
    if not isinstance(axes, list) or not all(isinstance(a, str) for a in axes):
        raise damaged(path, f"field 'axes' is {axes!r}, not a list of axis names")
    if not isinstance(info.get("reference") or {}, dict):
        raise damaged(path, f"field 'reference' is {info['reference']!r}, not a mapping")
    if not isinstance(info.get("study", ""), str):
        raise damaged(path, f"field 'study' is {info['study']!r}, not a name")
    return info


def read_table(path: Path) -> pd.DataFrame:
    """A parquet table; MresimError if it cannot be read."""
    try:
        return pd.read_parquet(path)
    except Exception as exc:  # pyarrow raises its own kinds for a damaged file
        detail = " ".join(str(exc).split())[:200]
        raise damaged(path, f"cannot read the table ({type(exc).__name__}: {detail})") from None


def need(path: Path, frame: pd.DataFrame, columns: list[str] | tuple[str, ...], why: str) -> None:
    """MresimError naming the first of ``columns`` that ``frame`` lacks."""
    for column in columns:
        if column not in frame.columns:
            raise damaged(path, f"column {column!r} is missing ({why})")


def numbers(path: Path, frame: pd.DataFrame, columns: list[str] | tuple[str, ...]) -> None:
    """MresimError naming the first of ``columns`` that holds something else than numbers."""
    for column in columns:
        if not pd.api.types.is_numeric_dtype(frame[column]) or pd.api.types.is_bool_dtype(
            frame[column]
        ):
            raise damaged(path, f"column {column!r} holds {frame[column].dtype}, not numbers")


def check_runs(path: Path, runs: pd.DataFrame, info: dict[str, Any]) -> None:
    """The columns of runs.parquet compare uses: the keys, and the axes of sweep.json."""
    if runs.empty:
        raise MresimError(f"{path.parent}: no run of the sweep finished; nothing to compare.")
    need(path, runs, RUNS_KEYS, "every sweep's runs table has it")
    axes = [a for a in info.get("axes", []) if a not in RUNS_KEYS]
    need(path, runs, axes, f"{path.parent / SWEEP_FILE} names it as an axis")
    if runs["run_id"].duplicated().any():
        twice = runs["run_id"][runs["run_id"].duplicated()].iloc[0]
        raise damaged(path, f"column 'run_id' holds {twice!r} twice")


def check_steps(path: Path, steps: pd.DataFrame) -> None:
    """The columns of steps.parquet compare uses, numbers where needed, each step once."""
    need(path, steps, STEPS_KEYS, "the curves need it")
    numbers(path, steps, STEPS_NUMBERS)
    twice = steps.duplicated(["run_id", "step"])
    if twice.any():
        row = steps[twice].iloc[0]
        raise damaged(
            path, f"columns 'run_id', 'step' hold ({row['run_id']!r}, {row['step']}) twice"
        )
