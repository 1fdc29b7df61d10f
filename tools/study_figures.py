"""What the study figures share (tools): each arm's figures and their drawing.

An arm's steps to a milestone are a Kaplan-Meier median with its 95 % interval (a run that
never got there is censored at its last step, never averaged; :mod:`mresim_phys.sweeps.survival`)
and how many runs did not get there; any other figure is a mean with its 95 % Student-t
interval (:func:`mresim_phys.sweeps.stats.mean_ci`). ``tools/make_drift_figure.py`` and
``tools/make_radio_figure.py`` draw them.
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from mresim_phys.sweeps.stats import mean_ci  # noqa: E402
from mresim_phys.sweeps.survival import censored, km_median  # noqa: E402

Look = tuple[str, str]  # line style and colour


def arm_figures(group: pd.DataFrame, milestone: str, means: Sequence[str]) -> dict[str, Any]:
    """One arm's runs: the milestone's median, interval and runs not reaching it, and the
    mean and interval of each of ``means`` (NaN where no run has the figure)."""
    median, low, high = km_median(censored(group, milestone))
    row: dict[str, Any] = {"runs": len(group), "median": median, "low": low, "high": high}
    row["not_reached"] = int(group[milestone].isna().sum())
    for name in means:
        column = group[name] if name in group else pd.Series(dtype=float)
        values = pd.to_numeric(column, errors="coerce").dropna().to_numpy()
        row[name] = float(np.mean(values)) if len(values) else math.nan
        row[f"{name}_ci"] = mean_ci(values) if len(values) > 1 else (math.nan, math.nan)
    return row


def draw_milestone(
    ax: Axes, x: pd.Series, rows: pd.DataFrame, label: str, look: Look, top: float
) -> None:
    """Medians with their intervals (an open upper end drawn to the top of the interval
    found); a triangle at ``top`` where the median is not reached; "k/n not reached"
    beside each point that has runs not reaching it."""
    finite = np.isfinite(rows["median"]).to_numpy()
    shown = rows[finite]
    low = shown["median"] - shown["low"].clip(upper=shown["median"])
    high = shown["high"].where(np.isfinite(shown["high"]), shown["median"]) - shown["median"]
    ax.errorbar(x[finite], shown["median"], yerr=[low, high], marker="o", capsize=3,
                linestyle=look[0], color=look[1], label=label)  # fmt: skip
    missing = x[~finite]
    ax.plot(missing, [top] * len(missing), "^", color=look[1], markersize=8)
    for xi, (_, row) in zip(x, rows.iterrows(), strict=True):
        if row["not_reached"]:
            short = not math.isfinite(row["median"])  # beside a triangle: the count alone
            y = top if short else row["median"]
            text = f"{row['not_reached']}/{row['runs']}{'' if short else ' not reached'}"
            ax.annotate(text, (xi, y), fontsize=6, xytext=(5, -3), textcoords="offset points",
                        color=look[1])  # fmt: skip


def draw_mean(
    ax: Axes, x: pd.Series, rows: pd.DataFrame, name: str, label: str, look: Look
) -> None:
    """Means of ``name`` with their 95 % intervals."""
    ci = np.array([list(v) for v in rows[f"{name}_ci"]], dtype=float)
    mean = rows[name].to_numpy(dtype=float)
    err = np.abs(np.vstack([mean - ci[:, 0], ci[:, 1] - mean]))
    ax.errorbar(x, mean, yerr=np.nan_to_num(err), marker="o", capsize=3, linestyle=look[0],
                color=look[1], label=label)  # fmt: skip


def print_table(data: pd.DataFrame) -> None:
    """The figures drawn, without their intervals' pairs."""
    with pd.option_context("display.width", 220, "display.max_columns", 24):
        print(data.drop(columns=[c for c in data.columns if c.endswith("_ci")]).to_string())


def run_tool(
    doc: str,
    image: str,
    table: Callable[[pd.DataFrame], pd.DataFrame],
    draw: Callable[[pd.DataFrame, Path], None],
    report: Callable[[pd.DataFrame], None] | None = None,
) -> None:
    """A figure tool's command line: read ``SWEEP_DIR/runs.parquet``, print the table
    (and ``report`` of the runs, if given), draw the figure (``--out``, default
    ``docs/images/<image>``)."""
    parser = argparse.ArgumentParser(description=doc.splitlines()[0])
    parser.add_argument("sweep", type=Path)
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "images" / image)
    args = parser.parse_args()
    runs = pd.read_parquet(args.sweep / "runs.parquet")
    data = table(runs)
    print_table(data)
    if report is not None:
        report(runs)
    draw(data, args.out)
    print(f"wrote {args.out}")


def save(fig: Figure, axes: Sequence[Axes], xlabel: str, out: Path, fontsize: int = 8) -> None:
    """Label every panel's x axis, give it a legend and a grid, and write the figure."""
    for ax in axes:
        ax.set_xlabel(xlabel)
        ax.legend(fontsize=fontsize)
        ax.grid(alpha=0.3)
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    plt.close(fig)
