"""Run data (output edge): what the plots read from a run folder, checked.

:func:`read_metrics` reads ``metrics.csv`` (pandas) and checks its columns and values;
:func:`run_label` names a run from its ``summary.json``; :func:`run_events` lists the
failures and blackouts of a run from its log (``log/steps.jsonl``: every event as the run
logged it, e.g. ``fail B``, ``blackout A,B (main) until 300``), or, for a run without a
log, the failures its ``metrics.csv`` shows (a robot's state turning ``failed``). A
missing, empty or damaged file is a MresimError naming it, never a pandas or JSON error.
"""

from __future__ import annotations

import csv
import json
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mresim_phys.errors import MresimError

REQUIRED = ("step", "explored", "known_at_base", "distance", "alive", "links")
UNTIL = re.compile(r"until (\d+)$")


@dataclass(frozen=True)
class RunEvent:
    """A failure or a blackout: its first step, its kind, its text, and a blackout's end."""

    step: int
    kind: str  # "failure" or "blackout"
    text: str
    until: int | None = None


def damaged(path: Path, what: str) -> MresimError:
    """The error for a run file that cannot be used."""
    return MresimError(
        f"{path}: {what}. The run folder is damaged or not one 'mresim run' wrote;"
        " run the scenario again to rewrite it."
    )


def read_metrics(run_dir: Path) -> Any:
    """The run's metrics as a DataFrame (numeric columns checked); MresimError otherwise."""
    import pandas as pd

    path = run_dir / "metrics.csv"
    if not path.is_file():
        raise MresimError(
            f"{run_dir} is not a run folder: it has no metrics.csv. Give the folder that"
            " 'mresim run' wrote (e.g. runs/<name>/seed-<seed>)."
        )
    try:
        df = pd.read_csv(path, encoding="utf-8")
    except (OSError, UnicodeDecodeError, ValueError, csv.Error) as exc:
        reason = str(exc).strip() or type(exc).__name__
        raise damaged(path, f"not a readable CSV file ({reason})") from None
    missing = [c for c in REQUIRED if c not in df.columns]
    if missing:
        raise damaged(path, f"lacks the columns {', '.join(missing)}")
    if df.empty:
        raise damaged(path, "no rows")
    numeric = [*REQUIRED, *(c for c in df.columns if c.startswith("distance_"))]
    for column in numeric:
        try:
            df[column] = pd.to_numeric(df[column])
        except (ValueError, TypeError):
            raise damaged(path, f"column {column} holds values that are not numbers") from None
    return df


def run_label(run_dir: Path) -> str:
    """``name seed N`` from the run's summary.json, else the folder path."""
    path = run_dir / "summary.json"
    if not path.exists():
        return str(run_dir)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise damaged(path, f"not readable JSON ({exc})") from None
    if not isinstance(data, dict):
        raise damaged(path, "not a JSON object")
    return f"{data.get('name', run_dir.name)} seed {data.get('seed', '?')}"


def event_of(step: int, text: str) -> RunEvent | None:
    """The failure or blackout a logged event text describes (None: another kind)."""
    if text.startswith("fail "):
        return RunEvent(step, "failure", text)
    if text.startswith("blackout ") and not text.startswith("blackout over"):
        until = UNTIL.search(text)
        return RunEvent(step, "blackout", text, int(until.group(1)) if until else None)
    return None


def logged_events(path: Path) -> list[RunEvent]:
    """The failures and blackouts of a run log's ``steps.jsonl``."""
    events = []
    try:
        with path.open(encoding="utf-8") as lines:
            for number, line in enumerate(lines, 1):
                if not line.strip():
                    continue
                try:
                    data = json.loads(line)
                    step, texts = int(data["step"]), list(data.get("events", []))
                except (ValueError, KeyError, TypeError, AttributeError) as exc:
                    raise damaged(path, f"line {number} is not a logged step ({exc})") from None
                events += [e for t in texts if (e := event_of(step, str(t))) is not None]
    except (OSError, UnicodeDecodeError) as exc:
        raise damaged(path, f"not readable ({exc})") from None
    return events


def state_failures(df: Any) -> list[RunEvent]:
    """Failures seen in metrics.csv: the first step each robot's state is ``failed``."""
    events = []
    for column in (c for c in df.columns if c.startswith("state_")):
        failed = df.loc[df[column] == "failed", "step"]
        if len(failed):
            name = column.removeprefix("state_")
            events.append(RunEvent(int(failed.iloc[0]), "failure", f"fail {name}"))
    return sorted(events, key=lambda e: e.step)


def run_events(run_dir: Path, df: Any) -> list[RunEvent]:
    """The run's failures and blackouts: from its log, else from ``df`` (its metrics)."""
    steps = run_dir / "log" / "steps.jsonl"
    return logged_events(steps) if steps.is_file() else state_failures(df)
