"""The drift study's figure (docs/localization.md): exploration and map consistency against drift.

Reads a sweep of ``studies/drift_alpha.yaml`` (its ``runs.parquet``) and draws, per
strategy, against the drift (the alphas as a multiple of the shipped scenarios'):

1. steps to 90 % explored: the Kaplan-Meier median and its 95 % interval (a run that never
   got there is censored at its last step, never averaged; an arrow where the median is
   not reached), with "k/n not reached" beside each point;
2. the base station's map consistency at the end: the cells it believes free that are
   walls and the cells it believes walls that are free, as fractions of the reachable area
   (mean and 95 % Student-t interval);
3. the team's mean position error over the run (mean and 95 % interval).

Run: ``python tools/make_drift_figure.py SWEEP_DIR [--out docs/images/drift_alpha.png]``;
it prints the table it draws.
"""

from __future__ import annotations

import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from study_figures import arm_figures, draw_mean, draw_milestone, run_tool, save

ALPHA = "team.localization.odometry.alpha"
STRATEGY = "team.strategy"
REFERENCE_A1 = 0.0002  # the shipped scenarios' a1
MILESTONE = "steps_to_explored_90"
MEANS = ("base_false_free", "base_false_occupied", "pose_error_mean")


def drift_of(value: object) -> float:
    """The drift of an arm: its a1 over the shipped scenarios' a1."""
    alpha = json.loads(value) if isinstance(value, str) else value
    return float(np.asarray(alpha, dtype=float)[0]) / REFERENCE_A1


def table(runs: pd.DataFrame) -> pd.DataFrame:
    """One row per (strategy, drift): the figures drawn."""
    runs = runs[runs["status"] == "done"].copy()
    runs["drift"] = runs[ALPHA].map(drift_of)
    rows = []
    for (strategy, drift), group in runs.groupby([STRATEGY, "drift"]):
        row = {"strategy": strategy, "drift": drift}
        rows.append(row | arm_figures(group, MILESTONE, MEANS))
    out: pd.DataFrame = pd.DataFrame(rows).sort_values(["strategy", "drift"])
    return out


def draw(data: pd.DataFrame, out: Path) -> None:
    """The three panels, one colour per strategy."""
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.6))
    for n, (strategy, rows) in enumerate(data.groupby("strategy")):
        colour, x = f"C{n}", rows["drift"]
        draw_milestone(axes[0], x, rows, str(strategy), ("-", colour), top_of(data))
        for name, style in (("base_false_free", "-"), ("base_false_occupied", "--")):
            label = f"{strategy}: {name[5:].replace('_', ' ')}"
            draw_mean(axes[1], x, rows, name, label, (style, colour))
        draw_mean(axes[2], x, rows, "pose_error_mean", str(strategy), ("-", colour))
    axes[0].set(title="steps to 90 % explored (Kaplan-Meier median, 95 %)", ylabel="steps")
    axes[1].set(title="base map at the end: wrong cells", ylabel="fraction of reachable area")
    axes[2].set(title="team's mean position error", ylabel="cells")
    save(fig, axes, "drift (alphas / the shipped scenarios')", out)


def top_of(data: pd.DataFrame) -> float:
    """Where a median not reached is drawn: above every finite median and bound."""
    finite = pd.concat([data["median"], data["low"]]).replace(np.inf, np.nan)
    return float(finite.max()) * 1.08 if finite.notna().any() else 1.0


if __name__ == "__main__":
    run_tool(__doc__, "drift_alpha.png", table, draw)
