"""``mresim compare`` (sweeps, compare): a sweep folder -> figures and a report.

Reads ``runs.parquet`` and ``steps.parquet``, forms arms by the ``--by`` columns (an axis
by its path or its last part: ``strategy`` = ``team.strategy``; default every axis),
computes each metric's figures (``sweeps/stats.py``), draws the figures
(``sweeps/figures.py``) and writes ``report.md`` and ``report.html``
(``sweeps/report.py``) into ``--out`` (default ``<sweep>/compare``).
"""

from __future__ import annotations

import difflib
from pathlib import Path
from typing import Any

import pandas as pd

from mresim_phys.errors import MresimError
from mresim_phys.sweeps.figures import (
    fault_axis,
    plot_curves,
    plot_degradation,
    plot_distribution,
)
from mresim_phys.sweeps.report import Section, write_reports
from mresim_phys.sweeps.stats import Grouping, arm_groups, compare_metric
from mresim_phys.sweeps.sweep_input import Sweep, damaged, need, numbers, read_sweep
from mresim_phys.sweeps.tables import RUNS_TABLE

DEFAULT_METRICS = (
    "steps_to_explored_90",
    "steps_to_known_at_base_90",
    "auc_explored",
    "auc_known_at_base",
    "final_explored",
    "robots_idle_with_frontier",  # run health (knowledge/health.py, docs/run-health.md)
    "idle_robot_steps",
    "stuck_robot_steps",
)


def resolve_column(name: str, columns: list[str], what: str) -> str:
    """A column by its full name or the last part of an axis path."""
    if name in columns:
        return name
    matches = [c for c in columns if c.rsplit(".", 1)[-1] == name]
    if len(matches) == 1:
        return matches[0]
    short = {c.rsplit(".", 1)[-1]: c for c in columns}
    close = difflib.get_close_matches(name, [*columns, *short], n=1)
    hint = f" Did you mean {close[0]!r}?" if close else ""
    raise MresimError(f"{what} {name!r}: the sweep has no such column.{hint} It has: {columns}.")


def grouping_for(sweep: Sweep, by: list[str] | None, reference: str | None) -> Grouping:
    """Arms by ``by`` (default: every axis), paired on the rest; the reference arm."""
    axes = sweep.axes or ["scenario"]
    columns = resolve_by(sweep, by) if by else axes
    pair_keys = ["scenario", "seed", *(a for a in axes if a not in columns and a != "scenario")]
    probe = Grouping(columns, pair_keys, ())
    keys = [k for k, _ in arm_groups(sweep.runs, probe)]
    if not keys:
        raise MresimError(f"{sweep.folder}: no run of the sweep finished; nothing to compare.")
    return Grouping(columns, pair_keys, pick_reference(keys, probe, reference, sweep.info))


def resolve_by(sweep: Sweep, by: list[str]) -> list[str]:
    """The ``--by`` names as columns of runs.parquet."""
    columns = [c for c in sweep.runs.columns if c not in ("run_id", "label", "status")]
    return [resolve_column(name, columns, "--by") for name in by]


def pick_reference(keys: list[Any], probe: Grouping, text: str | None, info: dict[str, Any]) -> Any:
    """The reference arm: ``--reference`` (an arm label or one value), else the study's
    ``reference`` values, else the first arm."""
    labels = [probe.label(k) for k in keys]
    if text is not None:
        hits = [
            k
            for k, label in zip(keys, labels, strict=True)
            if text == label or text in (str(v) for v in k)
        ]
        if len(hits) != 1:
            raise MresimError(f"--reference {text!r} names {len(hits)} arms; the arms: {labels}.")
        return hits[0]
    wanted = info.get("reference") or {}
    for key in keys:
        values = dict(zip(probe.by, key, strict=True))
        if wanted and all(values.get(c) == v for c, v in wanted.items() if c in values):
            return key
    return keys[0]


def run_compare(
    folder: Path,
    by: list[str] | None = None,
    metrics: list[str] | None = None,
    out: Path | None = None,
    reference: str | None = None,
    svg: bool = False,
) -> list[Path]:
    """Figures and report of the sweep in ``folder``; the files written."""
    sweep = read_sweep(folder)
    out = Path(out) if out is not None else sweep.folder / "compare"
    grouping = grouping_for(sweep, by, reference)
    chosen = choose_metrics(sweep, metrics)
    try:
        sections = [Section(m, *compare_metric(sweep.runs, m, grouping)) for m in chosen]
        figures = plot_curves(sweep.runs, sweep.steps, grouping, out, svg)
        figures += plot_distribution(sweep.runs, chosen[0], grouping, out, svg)
        fault = fault_axis(sweep.axes)
        if fault is not None:
            figures += plot_degradation(sweep.runs, chosen[0], fault, grouping, out, svg)
    except (KeyError, ValueError, TypeError, IndexError) as exc:  # values of other kinds
        detail = " ".join(str(exc).split())[:200]
        raise damaged(
            sweep.folder / RUNS_TABLE,
            f"its values (or steps.parquet's) are not what `mresim sweep` writes"
            f" ({type(exc).__name__}: {detail})",
        ) from None
    pictures = [p for p in figures if p.suffix == ".png"]
    return [*figures, *write_reports(out, sweep.runs, grouping, sections, pictures, sweep.title)]


def choose_metrics(sweep: Sweep, metrics: list[str] | None) -> list[str]:
    """The ``--metric`` columns (default: those of DEFAULT_METRICS the sweep has), checked."""
    numeric = [
        c
        for c in sweep.runs.columns
        if pd.api.types.is_numeric_dtype(sweep.runs[c]) or c.startswith("steps_to_")
    ]
    chosen = [
        resolve_column(m, numeric, "--metric")
        for m in metrics or DEFAULT_METRICS
        if metrics or m in numeric
    ]
    path = sweep.folder / RUNS_TABLE
    if not chosen:
        raise damaged(
            path,
            f"none of the default metrics ({', '.join(DEFAULT_METRICS)}) is a column of numbers;"
            " name one with --metric",
        )
    if any(m.startswith("steps_to_") for m in chosen):
        need(
            path,
            sweep.runs,
            ["steps"],
            "steps_to_ metrics need it: a threshold never reached counts as steps + 1",
        )
        numbers(path, sweep.runs, ["steps"])
    return chosen
