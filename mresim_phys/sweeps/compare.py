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
from mresim_phys.sweeps.censored_figures import plot_contrast, plot_km_degradation, plot_survival
from mresim_phys.sweeps.contrast import Design, contrasts
from mresim_phys.sweeps.figures import (
    fault_axis,
    plot_curves,
    plot_degradation,
    plot_distribution,
)
from mresim_phys.sweeps.report import Headline, write_reports
from mresim_phys.sweeps.report_tables import Section
from mresim_phys.sweeps.stats import Grouping, arm_groups, compare_metric
from mresim_phys.sweeps.survival import is_time_to_event
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
    "waiting_robot_steps",
    "robots_fruitless",
    "fruitless_robot_steps",
)
HEADLINE = "auc_known_at_base"  # the robustness contrast opening the report, when chosen


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


def compare_sweep(
    folder: Path,
    by: list[str] | None = None,
    metrics: list[str] | None = None,
    out: Path | None = None,
    reference: str | None = None,
    svg: bool = False,
    detect: float | None = None,
) -> tuple[list[Path], Headline | None]:
    """Figures and report of the sweep in ``folder``: the files written, and the report's
    headline robustness contrast (None without a fault axis and two strategies)."""
    sweep = read_sweep(folder)
    out = Path(out) if out is not None else sweep.folder / "compare"
    grouping = grouping_for(sweep, by, reference)
    chosen = choose_metrics(sweep, metrics)
    design = contrast_design(grouping, fault_axis(sweep.axes))
    try:
        sections = [section(sweep.runs, m, grouping, design, detect) for m in chosen]
        headline = pick_headline(sections, design)
        figures = draw(sweep.runs, sweep.steps, chosen[0], grouping, design, out, svg)
        if headline is not None:
            figures += plot_contrast(
                headline.section.contrasts, headline.section.metric, headline.axis, out, svg
            )
    except (KeyError, ValueError, TypeError, IndexError) as exc:  # values of other kinds
        detail = " ".join(str(exc).split())[:200]
        raise damaged(
            sweep.folder / RUNS_TABLE,
            f"its values (or steps.parquet's) are not what `mresim sweep` writes"
            f" ({type(exc).__name__}: {detail})",
        ) from None
    pictures = [p for p in figures if p.suffix == ".png"]
    written = write_reports(out, sweep.runs, grouping, sections, pictures, sweep.title, headline)
    return [*figures, *written], headline


def section(
    runs: pd.DataFrame,
    metric: str,
    grouping: Grouping,
    design: Design | None,
    detect: float | None,
) -> Section:
    """One metric's figures, comparisons and (with a fault axis) robustness contrasts."""
    found = (
        [] if design is None else contrasts(runs, metric, design, grouping_label(design), detect)
    )
    return Section(metric, *compare_metric(runs, metric, grouping), found)


def draw(
    runs: pd.DataFrame,
    steps: pd.DataFrame,
    metric: str,
    grouping: Grouping,
    design: Design | None,
    out: Path,
    svg: bool,
) -> list[Path]:
    """The curves, the distribution of ``metric`` and its degradation over the fault axis
    (Kaplan-Meier figures for a steps-to-threshold metric)."""
    figures = plot_curves(runs, steps, grouping, out, svg)
    timed = is_time_to_event(metric)
    figures += (plot_survival if timed else plot_distribution)(runs, metric, grouping, out, svg)
    if design is not None:
        degrade = plot_km_degradation if timed else plot_degradation
        figures += degrade(runs, metric, design.axis, grouping, out, svg)
    return figures


def contrast_design(grouping: Grouping, axis: str | None) -> Design | None:
    """The robustness contrast's design when the arms are split by a fault axis: the other
    ``by`` columns form the groups; the reference arm's level is the baseline."""
    if axis is None or axis not in grouping.by:
        return None
    baseline = grouping.reference[grouping.by.index(axis)]
    groups = [c for c in grouping.by if c != axis] or ["scenario"]
    return Design(axis, groups, grouping.pair_keys, baseline)


def grouping_label(design: Design) -> Any:
    """``strategy=frontier`` for a group of the design's group columns."""

    def label(key: tuple[Any, ...]) -> str:
        return ", ".join(
            f"{c.rsplit('.', 1)[-1]}={v}" for c, v in zip(design.groups, key, strict=True)
        )

    return label


def pick_headline(sections: list[Section], design: Design | None) -> Headline | None:
    """The robustness contrast that opens the report: auc_known_at_base's when chosen,
    else the first metric's; none without a fault axis or a second group."""
    if design is None or not any(s.contrasts for s in sections):
        return None
    chosen = next((s for s in sections if s.metric == HEADLINE), sections[0])
    return Headline(chosen, design.axis) if chosen.contrasts else None


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
