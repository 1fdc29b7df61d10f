"""Sweep figures (sweeps, compare): matplotlib plots of a sweep's arms.

* ``curves``: explored and known-at-base against the step, the mean of each arm with its
  95 % confidence band, clipped to [0, 1] (a run that stopped early keeps its last value to
  the longest run's end, as a run stopped by a rule keeps what it knew);
* ``distribution``: a box plot of a metric per arm, over the runs that have a value;
* ``degradation``: for a fault axis (``failures`` or a ``faults.*`` path), the metric's
  mean and 95 % interval against the axis value, one line per group of the other
  ``--by`` columns (the strategies).

A steps-to-threshold metric is censored and never averaged: its distribution and
degradation figures are Kaplan-Meier figures (``sweeps/censored_figures.py``).

Each figure is written as PNG (and SVG when asked) with the Agg backend.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from scipy import stats

from mresim_phys.output.files import atomic_path
from mresim_phys.sweeps.stats import Grouping, arm_groups, metric_values

CURVES = ("explored", "known_at_base")


def save(fig: Any, out: Path, name: str, svg: bool) -> list[Path]:
    """Write ``fig`` as ``name``.png (and .svg); close it; the paths."""
    out.mkdir(parents=True, exist_ok=True)
    paths = [out / f"{name}.png"] + ([out / f"{name}.svg"] if svg else [])
    try:
        for path in paths:  # whole or not at all: a full disk leaves no half a figure
            with atomic_path(path) as tmp:
                fig.savefig(tmp, dpi=110, bbox_inches="tight", format=path.suffix[1:])
    finally:
        plt.close(fig)
    return paths


def band(matrix: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mean and 95 % t band over the rows of ``matrix`` (runs x steps)."""
    mean = matrix.mean(axis=0)
    n = matrix.shape[0]
    if n < 2:
        return mean, mean, mean
    half = stats.t.ppf(0.975, n - 1) * matrix.std(axis=0, ddof=1) / np.sqrt(n)
    return mean, mean - half, mean + half


def run_matrix(steps: pd.DataFrame, run_ids: list[str], column: str, last: int) -> np.ndarray:
    """``column`` of each run at steps 0..last (runs that ended keep their last value)."""
    mine = steps[steps["run_id"].isin(run_ids)]
    table = mine.pivot(index="step", columns="run_id", values=column)
    matrix: np.ndarray = table.reindex(range(last + 1)).ffill().to_numpy(dtype=float).T
    return matrix


def plot_curves(
    runs: pd.DataFrame, steps: pd.DataFrame, grouping: Grouping, out: Path, svg: bool
) -> list[Path]:
    """Explored and known-at-base against the step, mean and 95 % band per arm."""
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5), sharey=True)
    last = int(steps["step"].max()) if len(steps) else 0
    x = np.arange(last + 1)
    for key, group in arm_groups(runs, grouping):
        for ax, column in zip(axes, CURVES, strict=True):
            mean, low, high = band(run_matrix(steps, list(group["run_id"]), column, last))
            (line,) = ax.plot(x, mean, label=grouping.label(key), linewidth=1.4)
            low, high = np.clip(low, 0, 1), np.clip(high, 0, 1)  # fractions: the band too
            ax.fill_between(x, low, high, color=line.get_color(), alpha=0.2, linewidth=0)
    for ax, column in zip(axes, CURVES, strict=True):
        ax.set_title(f"{column.replace('_', ' ')} (mean, 95 % CI)")
        ax.set_xlabel("step")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("fraction of reachable free space")
    axes[1].legend(fontsize=8, loc="lower right")
    return save(fig, out, "curves", svg)


def plot_distribution(
    runs: pd.DataFrame, metric: str, grouping: Grouping, out: Path, svg: bool
) -> list[Path]:
    """A box plot of ``metric`` per arm."""
    groups = arm_groups(runs, grouping)
    fig, ax = plt.subplots(figsize=(max(5.0, 1.2 * len(groups) + 2), 4.5))
    data = [metric_values(g, metric).dropna().to_numpy() for _, g in groups]
    ax.boxplot(data, showmeans=True)
    ax.set_xticks(range(1, len(groups) + 1), [grouping.label(k) for k, _ in groups])
    ax.tick_params(axis="x", labelrotation=20, labelsize=8)
    ax.set_ylabel(metric)
    ax.set_title(f"{metric} per arm")
    ax.grid(alpha=0.3, axis="y")
    return save(fig, out, f"distribution_{metric}", svg)


def fault_axis(axes: list[str]) -> str | None:
    """The sweep's fault axis: ``failures`` or the first ``faults.*`` path."""
    return next((a for a in axes if a == "failures" or a.startswith("faults.")), None)


def fault_lines(
    runs: pd.DataFrame, axis: str, grouping: Grouping
) -> tuple[list[Any], list[tuple[str, pd.DataFrame]]]:
    """The fault axis's levels (sweep order) and the done runs of each line of a
    degradation figure: one per group of the other ``by`` columns, with its label."""
    others = [c for c in grouping.by if c != axis] or ["scenario"]
    done = runs[runs["status"] == "done"]
    levels = list(dict.fromkeys(done[axis].tolist()))
    lines = [
        (", ".join(str(k) for k in (key if isinstance(key, tuple) else (key,))), group)
        for key, group in done.groupby(others, sort=False, dropna=False)
    ]
    return levels, lines


def finish_degradation(
    fig: Any, ax: Any, levels: list[Any], axis: str, ylabel: str, title: str
) -> None:
    """Ticks, labels, legend and grid of a degradation figure."""
    ax.set_xticks(range(len(levels)), ["none" if v != v or v is None else str(v) for v in levels])
    ax.set_xlabel(axis)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)


def plot_degradation(
    runs: pd.DataFrame, metric: str, axis: str, grouping: Grouping, out: Path, svg: bool
) -> list[Path]:
    """``metric`` against the fault axis, one line per group of the other ``by`` columns."""
    levels, lines = fault_lines(runs, axis, grouping)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for label, group in lines:
        means, lows, highs = [], [], []
        for level in levels:
            values = metric_values(group[same(group[axis], level)], metric).dropna().to_numpy()
            mean, low, high = band(values.reshape(-1, 1)) if len(values) else ([np.nan],) * 3
            means.append(mean[0])
            lows.append(low[0])
            highs.append(high[0])
        (line,) = ax.plot(range(len(levels)), means, marker="o", label=label)
        ax.fill_between(range(len(levels)), lows, highs, color=line.get_color(), alpha=0.2)
    finish_degradation(
        fig, ax, levels, axis, f"{metric} (mean, 95 % CI)", f"{metric} against {axis}"
    )
    return save(fig, out, f"degradation_{metric}", svg)


def same(column: pd.Series, level: Any) -> pd.Series:
    """Rows of ``column`` equal to ``level`` (NaN matching NaN)."""
    rows: pd.Series = column.isna() if level is None or level != level else column == level
    return rows
