"""Figures of censored times and robustness contrasts (sweeps, compare).

* ``distribution_<metric>`` for a steps-to-threshold metric: each arm's Kaplan-Meier curve,
  the share of runs that have not yet reached the threshold against the step, with a tick
  where a run stopped without reaching it (censored), and the share never reached in the
  legend;
* ``degradation_<metric>`` for such a metric: the Kaplan-Meier median and its 95 % interval
  against the fault axis, an arrow where the median is not reached, and "k/n not reached"
  beside every point;
* ``contrast_<metric>``: the robustness contrasts (``sweeps/contrast.py``), each pair of
  groups a line of mean contrasts with their 95 % intervals against the fault level, the
  side of 0 on which A is more robust named on the axis.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from scipy import stats

from mresim_phys.sweeps.contrast import Contrast, higher_is_better
from mresim_phys.sweeps.figures import fault_lines, finish_degradation, same, save
from mresim_phys.sweeps.stats import Grouping, arm_groups
from mresim_phys.sweeps.survival import arm_survival, censored, event_times, horizon_of


def km_steps(data: Any) -> tuple[np.ndarray, np.ndarray]:
    """The Kaplan-Meier curve as step-plot points, from step 0 at 1."""
    if data.num_censored() == len(data):
        return np.array([0.0]), np.array([1.0])
    curve = stats.ecdf(data).sf
    return np.r_[0.0, curve.quantiles], np.r_[1.0, curve.probabilities]


def plot_survival(
    runs: pd.DataFrame, metric: str, grouping: Grouping, out: Path, svg: bool
) -> list[Path]:
    """Each arm's Kaplan-Meier curve of ``metric`` with its censored runs marked."""
    fig, ax = plt.subplots(figsize=(8, 4.8))
    end = horizon_of(runs)
    for key, group in arm_groups(runs, grouping):
        data = censored(group, metric, end)
        x, y = km_steps(data)
        share = data.num_censored() / len(data) if len(data) else math.nan
        label = f"{grouping.label(key)} ({share:.0%} not reached)"
        (line,) = ax.step(x, y, where="post", label=label, linewidth=1.4)
        cut = np.sort(event_times(group, metric, end)[1])
        if len(cut):
            at = np.interp(cut, x, y, left=1.0)
            ax.plot(cut, at, "|", color=line.get_color(), markersize=10, markeredgewidth=1.5)
    ax.set_xlabel("step")
    ax.set_ylabel("share of runs not yet at the threshold")
    ax.set_title(f"{metric}: Kaplan-Meier curves (| a run that never reached it)")
    ax.set_ylim(-0.02, 1.02)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    return save(fig, out, f"distribution_{metric}", svg)


def plot_km_degradation(
    runs: pd.DataFrame, metric: str, axis: str, grouping: Grouping, out: Path, svg: bool
) -> list[Path]:
    """The Kaplan-Meier median of ``metric`` and its interval against the fault axis."""
    levels, lines = fault_lines(runs, axis, grouping)
    end = horizon_of(runs)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for label, group in lines:
        points = [arm_survival(label, group[same(group[axis], v)], metric, end) for v in levels]
        top = max((p.longest for p in points if p.n), default=1.0)
        medians = [min(p.median, top) for p in points]
        lows = [min(p.ci_low, top) for p in points]
        highs = [min(p.ci_high, top) for p in points]
        (line,) = ax.plot(range(len(levels)), medians, marker="o", label=label)
        ax.fill_between(range(len(levels)), lows, highs, color=line.get_color(), alpha=0.2)
        for i, p in enumerate(points):
            ax.annotate(
                f"{p.not_reached}/{p.n} not reached",
                (i, medians[i]),
                fontsize=7,
                textcoords="offset points",
                xytext=(4, 4),
                color=line.get_color(),
            )
            if math.isinf(p.median):
                ax.plot(i, top, "^", color=line.get_color(), markersize=9)
    ylabel = f"{metric} (Kaplan-Meier median, 95 % CI)"
    finish_degradation(
        fig, ax, levels, axis, ylabel, f"{metric} against {axis} (^ median not reached)"
    )
    return save(fig, out, f"degradation_{metric}", svg)


def plot_contrast(
    contrasts: list[Contrast], metric: str, axis: str, out: Path, svg: bool
) -> list[Path]:
    """The robustness contrasts against the fault level, with their intervals."""
    fig, ax = plt.subplots(figsize=(7, 4.5))
    pairs = list(dict.fromkeys((c.a, c.b) for c in contrasts))
    levels = list(dict.fromkeys(str(c.level) for c in contrasts))
    for i, (a, b) in enumerate(pairs):
        mine = [c for c in contrasts if (c.a, c.b) == (a, b) and c.estimated]
        x = [levels.index(str(c.level)) + 0.08 * (i - (len(pairs) - 1) / 2) for c in mine]
        y = [c.mean for c in mine]
        errors = [[c.mean - c.ci_low for c in mine], [c.ci_high - c.mean for c in mine]]
        ax.errorbar(x, y, yerr=errors, marker="o", capsize=4, label=f"A={a}, B={b}")
    ax.axhline(0.0, color="black", linewidth=0.8)
    ax.set_xticks(range(len(levels)), levels)
    ax.set_xlim(-0.5, len(levels) - 0.5)
    better = "above" if higher_is_better(metric) else "below"
    ax.set_xlabel(f"{axis} (against the baseline {contrasts[0].baseline})")
    ax.set_ylabel(f"contrast of {metric}\n(A more robust {better} 0)")
    ax.set_title("Is A more robust than B? Paired difference of degradations, 95 % CI")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    return save(fig, out, f"contrast_{metric}", svg)
