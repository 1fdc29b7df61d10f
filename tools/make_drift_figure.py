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

import argparse
import json
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

ALPHA = "team.localization.odometry.alpha"
STRATEGY = "team.strategy"
REFERENCE_A1 = 0.0002  # the shipped scenarios' a1
MILESTONE = "steps_to_explored_90"


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
        median, low, high = km_median(censored(group, MILESTONE))
        row = {"strategy": strategy, "drift": drift, "runs": len(group)}
        row |= {"median": median, "low": low, "high": high}
        row["not_reached"] = int(group[MILESTONE].isna().sum())
        for name in ("base_false_free", "base_false_occupied", "pose_error_mean"):
            values = pd.to_numeric(group[name], errors="coerce").dropna().to_numpy()
            row[name] = float(np.mean(values)) if len(values) else math.nan
            row[f"{name}_ci"] = mean_ci(values)
        rows.append(row)
    out: pd.DataFrame = pd.DataFrame(rows).sort_values(["strategy", "drift"])
    return out


def draw(data: pd.DataFrame, out: Path) -> None:
    """The three panels, one colour per strategy."""
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.6))
    for n, (strategy, rows) in enumerate(data.groupby("strategy")):
        colour, x = f"C{n}", rows["drift"].to_numpy()
        _milestone(axes[0], rows, str(strategy), colour)
        for name, style in (("base_false_free", "-"), ("base_false_occupied", "--")):
            label = f"{strategy}: {name[5:].replace('_', ' ')}"
            _with_ci(axes[1], x, rows, name, label, (style, colour))
        _with_ci(axes[2], x, rows, "pose_error_mean", str(strategy), ("-", colour))
    axes[0].set(title="steps to 90 % explored (Kaplan-Meier median, 95 %)", ylabel="steps")
    axes[1].set(title="base map at the end: wrong cells", ylabel="fraction of reachable area")
    axes[2].set(title="team's mean position error", ylabel="cells")
    for ax in axes:
        ax.set_xlabel("drift (alphas / the shipped scenarios')")
        ax.legend(fontsize=8)
        ax.grid(alpha=0.3)
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    plt.close(fig)


def _milestone(ax: Axes, rows: pd.DataFrame, label: str, colour: str) -> None:
    """Medians with their intervals (an open upper end drawn to the top of the interval
    found); where the median is not reached, a triangle at the top of the panel."""
    shown = rows[np.isfinite(rows["median"])]
    low = shown["median"] - shown["low"].clip(upper=shown["median"])
    high = shown["high"].where(np.isfinite(shown["high"]), shown["median"]) - shown["median"]
    ax.errorbar(shown["drift"], shown["median"], yerr=[low, high], marker="o", capsize=3,
                label=label, color=colour)  # fmt: skip
    finite = pd.concat([rows["median"], rows["low"]]).replace(math.inf, np.nan)
    top = float(finite.max()) * 1.08 if finite.notna().any() else 1.0
    missing = rows[~np.isfinite(rows["median"])]
    ax.plot(missing["drift"], [top] * len(missing), "^", color=colour, markersize=9,
            label=f"{label}: median not reached" if len(missing) else None)  # fmt: skip
    for _, row in rows.iterrows():
        y = row["median"] if math.isfinite(row["median"]) else top
        ax.annotate(f"{row['not_reached']}/{row['runs']} not reached", (row["drift"], y),
                    fontsize=7, xytext=(4, 4), textcoords="offset points")  # fmt: skip


def _with_ci(
    ax: Axes, x: np.ndarray, rows: pd.DataFrame, name: str, label: str, look: tuple[str, str]
) -> None:
    """Means with their 95 % intervals (``look``: line style and colour)."""
    ci = np.array([list(v) for v in rows[f"{name}_ci"]])
    mean = rows[name].to_numpy()
    err = np.abs(np.vstack([mean - ci[:, 0], ci[:, 1] - mean]))
    ax.errorbar(x, mean, yerr=np.nan_to_num(err), marker="o", capsize=3, linestyle=look[0],
                color=look[1], label=label)  # fmt: skip


def main() -> None:
    """Read the sweep, print the table, draw the figure."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("sweep", type=Path)
    parser.add_argument("--out", type=Path, default=ROOT / "docs/images/drift_alpha.png")
    args = parser.parse_args()
    data = table(pd.read_parquet(args.sweep / "runs.parquet"))
    with pd.option_context("display.width", 200, "display.max_columns", 20):
        print(data.drop(columns=[c for c in data.columns if c.endswith("_ci")]).to_string())
    draw(data, args.out)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
