"""The radio study's figure (docs/communication.md): who gets knowledge home as links shrink.

Reads a sweep of ``studies/radio_capacity.yaml`` (its ``runs.parquet``) and draws, per
strategy, against each link's capacity (unlimited, then bytes per step), without bursts
(solid) and with Gilbert-Elliott bursts (dashed):

1. steps to 90 % known at the base: the Kaplan-Meier median and its 95 % interval (a run
   that never got there is censored at its last step, never averaged; a triangle where
   the median is not reached), with "k/n" not reached beside each point;
2. the share of the explorable area the base holds at the end (mean and 95 % Student-t
   interval);
3. the meetings kept, of those kept or missed (strategies that plan meetings; mean and 95 %
   interval over the runs that judged any).

Run: ``python tools/make_radio_figure.py SWEEP_DIR [--out docs/images/radio_capacity.png]``;
it prints the table it draws.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from matplotlib.axes import Axes

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from mresim_phys.sweeps.stats import mean_ci  # noqa: E402
from mresim_phys.sweeps.survival import censored, km_median  # noqa: E402

STRATEGY = "team.strategy"
CAPACITY = "communication.capacity"
BURSTS = "communication.bursts"
MILESTONE = "steps_to_known_at_base_90"
CAPACITIES = [None, 20000, 5000, 2000]  # the study's axis, left to right


def capacity_label(value: object) -> str:
    """A capacity as the x axis names it."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "unlimited"
    return f"{int(float(str(value))):,} B"


def bursty(value: object) -> bool:
    """Whether an arm had burst losses (its axis value is not null)."""
    return value is not None and str(value) not in ("None", "null", "nan", "")


def table(runs: pd.DataFrame) -> pd.DataFrame:
    """One row per (strategy, bursts, capacity): the figures drawn."""
    runs = runs[runs["status"] == "done"].copy()
    runs["capacity"] = runs[CAPACITY].map(capacity_label)
    runs["bursts"] = runs[BURSTS].map(bursty)
    order = [capacity_label(c) for c in CAPACITIES]
    rows = []
    for (strategy, bursts, capacity), group in runs.groupby([STRATEGY, "bursts", "capacity"]):
        median, low, high = km_median(censored(group, MILESTONE))
        row = {"strategy": strategy, "bursts": bursts, "capacity": capacity}
        row |= {"x": order.index(str(capacity)), "runs": len(group)}
        row |= {"median": median, "low": low, "high": high}
        row["not_reached"] = int(group[MILESTONE].isna().sum())
        for name in ("final_known_at_base", "meeting_keep_rate"):
            values = pd.to_numeric(group.get(name), errors="coerce").dropna().to_numpy()
            row[name] = float(np.mean(values)) if len(values) else math.nan
            row[f"{name}_ci"] = mean_ci(values) if len(values) > 1 else (math.nan, math.nan)
        rows.append(row)
    out: pd.DataFrame = pd.DataFrame(rows).sort_values(["strategy", "bursts", "x"])
    return out


def draw(data: pd.DataFrame, out: Path) -> None:
    """The three panels, one colour per strategy, dashed with bursts."""
    fig, axes = plt.subplots(1, 3, figsize=(16, 4.8))
    strategies = sorted(data["strategy"].unique())
    for (strategy, bursts), rows in data.groupby(["strategy", "bursts"]):
        colour = f"C{strategies.index(strategy)}"
        style = "--" if bursts else "-"
        label = f"{strategy}{', bursts' if bursts else ''}"
        shift = 0.06 * (strategies.index(strategy) - 1) + (0.02 if bursts else -0.02)
        _milestone(axes[0], rows, label, (style, colour), shift)
        _with_ci(axes[1], rows, "final_known_at_base", label, (style, colour), shift)
        if rows["meeting_keep_rate"].notna().any():
            _with_ci(axes[2], rows, "meeting_keep_rate", label, (style, colour), shift)
    axes[0].set(title="steps to 90 % known at the base (Kaplan-Meier median, 95 %)",
                ylabel="steps")  # fmt: skip
    axes[1].set(title="known at the base at the end", ylabel="fraction of explorable area")
    axes[2].set(title="meetings kept (of kept or missed)", ylabel="keep rate")
    ticks = [capacity_label(c) for c in CAPACITIES]
    for ax in axes:
        ax.set_xticks(range(len(ticks)), ticks)
        ax.set_xlabel("capacity per link and step")
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    plt.close(fig)


def _milestone(
    ax: Axes, rows: pd.DataFrame, label: str, look: tuple[str, str], shift: float
) -> None:
    """Medians with their intervals; a triangle at the top where the median is not
    reached; "k/n" not reached beside each point."""
    x = rows["x"] + shift
    finite = np.isfinite(rows["median"])
    shown = rows[finite]
    low = shown["median"] - shown["low"].clip(upper=shown["median"])
    high = shown["high"].where(np.isfinite(shown["high"]), shown["median"]) - shown["median"]
    ax.errorbar(x[finite], shown["median"], yerr=[low, high], marker="o", capsize=3,
                linestyle=look[0], color=look[1], label=label)  # fmt: skip
    top = 620.0
    ax.plot(x[~finite], [top] * int((~finite).sum()), "^", color=look[1], markersize=8)
    for xi, (_, row) in zip(x, rows.iterrows(), strict=True):
        if row["not_reached"]:
            y = row["median"] if math.isfinite(row["median"]) else top
            ax.annotate(f"{row['not_reached']}/{row['runs']}", (xi, y), fontsize=6,
                        xytext=(3, 3), textcoords="offset points", color=look[1])  # fmt: skip


def _with_ci(
    ax: Axes, rows: pd.DataFrame, name: str, label: str, look: tuple[str, str], shift: float
) -> None:
    """Means with their 95 % intervals (``look``: line style and colour)."""
    ci = np.array([list(v) for v in rows[f"{name}_ci"]], dtype=float)
    mean = rows[name].to_numpy(dtype=float)
    err = np.abs(np.vstack([mean - ci[:, 0], ci[:, 1] - mean]))
    ax.errorbar(rows["x"] + shift, mean, yerr=np.nan_to_num(err), marker="o", capsize=3,
                linestyle=look[0], color=look[1], label=label)  # fmt: skip


def main() -> None:
    """Read the sweep, print the table, draw the figure."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("sweep", type=Path)
    parser.add_argument("--out", type=Path, default=ROOT / "docs/images/radio_capacity.png")
    args = parser.parse_args()
    data = table(pd.read_parquet(args.sweep / "runs.parquet"))
    with pd.option_context("display.width", 220, "display.max_columns", 20):
        print(data.drop(columns=[c for c in data.columns if c.endswith("_ci")]).to_string())
    draw(data, args.out)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
