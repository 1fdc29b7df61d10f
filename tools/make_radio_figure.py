"""The radio study's figure (docs/communication.md): who gets knowledge home as links shrink.

Reads a sweep of ``studies/radio_capacity.yaml`` (its ``runs.parquet``) and draws, per
strategy, against each link's capacity (unlimited, then bytes per step), without bursts
(solid) and with Gilbert-Elliott bursts (dashed):

1. steps to 90 % known at the base: the Kaplan-Meier median and its 95 % interval (a run
   that never got there is censored at its last step, never averaged; a triangle where
   the median is not reached), with "k/n" not reached beside each point;
2. the share of the explorable area the base holds at the end (mean and 95 % Student-t
   interval);
3. the mean share of the robots in the base's linked group over the run
   (``connected_to_base``; mean and 95 % interval).

Run: ``python tools/make_radio_figure.py SWEEP_DIR [--out docs/images/radio_capacity.png]``;
it prints the table it draws, then every pair of strategies' paired difference in the
base's share at the end with its interval.
"""

from __future__ import annotations

import math
from itertools import combinations
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import pandas as pd
from scipy import stats
from study_figures import arm_figures, draw_mean, draw_milestone, run_tool, save

STRATEGY = "team.strategy"
CAPACITY = "communication.capacity"
BURSTS = "communication.bursts"
MILESTONE = "steps_to_known_at_base_90"
MEANS = ("final_known_at_base", "connected_to_base_mean")
CAPACITIES = [None, 20000, 5000, 2000]  # the study's axis, left to right
TOP = 615.0  # steps: where medians not reached are drawn (the study's cap is 600), stacked


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
        row = {"strategy": strategy, "bursts": bursts, "capacity": capacity}
        row["x"] = order.index(str(capacity))
        rows.append(row | arm_figures(group, MILESTONE, MEANS))
    out: pd.DataFrame = pd.DataFrame(rows).sort_values(["strategy", "bursts", "x"])
    return out


def draw(data: pd.DataFrame, out: Path) -> None:
    """The three panels, one colour per strategy, dashed with bursts."""
    fig, axes = plt.subplots(1, 3, figsize=(16, 4.8))
    strategies = sorted(data["strategy"].unique())
    for (strategy, bursts), rows in data.groupby(["strategy", "bursts"]):
        n = strategies.index(strategy)
        look = ("--" if bursts else "-", f"C{n}")
        label = f"{strategy}{', bursts' if bursts else ''}"
        x = rows["x"] + 0.06 * (n - 1) + (0.02 if bursts else -0.02)
        draw_milestone(axes[0], x, rows, label, look, TOP + 12 * (2 * n + bursts))
        draw_mean(axes[1], x, rows, "final_known_at_base", label, look)
        draw_mean(axes[2], x, rows, "connected_to_base_mean", label, look)
    axes[0].set(title="steps to 90 % known at the base (Kaplan-Meier median, 95 %)",
                ylabel="steps")  # fmt: skip
    axes[1].set(title="known at the base at the end", ylabel="fraction of explorable area")
    axes[2].set(title="robots in the base's linked group", ylabel="mean share over the run")
    ticks = [capacity_label(c) for c in CAPACITIES]
    for ax in axes:
        ax.set_xticks(range(len(ticks)), ticks)
    save(fig, axes, "capacity per link and step", out, 7)


def paired_contrasts(runs: pd.DataFrame) -> None:
    """Print, per capacity and bursts, each pair of strategies' paired difference in the
    base's share at the end (runs paired on seed: the same radio draws), with its 95 %
    Student-t interval (``scipy.stats.ttest_rel``): the claims docs/communication.md makes."""
    done = runs[runs["status"] == "done"].copy()
    done["capacity"] = done[CAPACITY].map(capacity_label)
    done["bursts"] = done[BURSTS].map(bursty)
    print("\npaired on seed, final_known_at_base: A - B, mean [95 % interval] (seeds)")
    for (capacity, bursts), arm in done.groupby(["capacity", "bursts"], sort=False):
        by_seed = arm.pivot_table(index="seed", columns=STRATEGY, values="final_known_at_base")
        for a, b in combinations(sorted(by_seed.columns), 2):
            pair = by_seed[[a, b]].dropna()
            if len(pair) < 2:
                continue
            interval = stats.ttest_rel(pair[a], pair[b]).confidence_interval()
            mean = float((pair[a] - pair[b]).mean())
            where = f"{capacity:>9}{' bursts' if bursts else '       '}"
            low, high = interval.low, interval.high
            print(f"  {where}  {a} - {b}: {mean:+.3f} [{low:+.3f}, {high:+.3f}] ({len(pair)})")


if __name__ == "__main__":
    run_tool(__doc__, "radio_capacity.png", table, draw, paired_contrasts)
