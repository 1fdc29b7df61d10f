"""The clock study's figure (docs/clocks.md): what a late decision costs each strategy.

Reads a sweep of ``studies/clock_delay.yaml`` (its ``runs.parquet``) and draws, per
strategy, against each arm's clock (none, a compute delay of 2, 5 and 10 steps, a
decision period of 10 steps):

1. steps to 90 % known at the base: the Kaplan-Meier median and its 95 % interval (a run
   that never got there is censored at its last step, never averaged; a triangle where
   the median is not reached), with "k/n not reached" beside each point;
2. steps to 90 % explored, the same way;
3. the meetings role-based pairs kept, and the robot-steps their clocks or their
   strategies held the robots still (``waiting_robot_steps``; means and 95 % Student-t
   intervals).

Run: ``python tools/make_clock_figure.py SWEEP_DIR [--out docs/images/clock_delay.png]``;
it prints the table it draws, then, for each clock, whether a late decision costs
role-based pairs more than frontier explorers: the paired (by seed: common random
numbers) difference in differences of the steps to 90 % known at the base, (role_based
with the clock - without) - (frontier with the clock - without), with its 95 % Student-t
interval; not computed for a clock where a run of the four never got there (censored).
"""

from __future__ import annotations

import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from scipy import stats
from study_figures import arm_figures, draw_mean, draw_milestone, run_tool, save

STRATEGY = "team.strategy"
CLOCK = "team.clock"
MILESTONES = ("steps_to_known_at_base_90", "steps_to_explored_90")
MEANS = ("meetings_kept", "waiting_robot_steps")
ARMS = ["none", "delay 2", "delay 5", "delay 10", "period 10"]  # the x axis, left to right
TOP = 930.0  # steps: where medians not reached are drawn (the study's cap is 900)


def clock_label(value: object) -> str:
    """An arm's clock as the x axis names it."""
    if value is None or (isinstance(value, float) and np.isnan(value)):
        return "none"
    clock = json.loads(value) if isinstance(value, str) else dict(value)  # type: ignore[call-overload]
    if "compute_delay" in clock:
        return f"delay {clock['compute_delay']}"
    return f"period {clock['decision_period']}"


def table(runs: pd.DataFrame) -> pd.DataFrame:
    """One row per (strategy, clock, milestone): the figures drawn."""
    runs = runs[runs["status"] == "done"].copy()
    runs["clock"] = runs[CLOCK].map(clock_label)
    rows = []
    for (strategy, clock), group in runs.groupby([STRATEGY, "clock"]):
        for milestone in MILESTONES:
            row = {"strategy": strategy, "clock": clock, "milestone": milestone}
            rows.append(row | arm_figures(group, milestone, MEANS))
    out = pd.DataFrame(rows)
    out["x"] = out["clock"].map(ARMS.index)
    return out.sort_values(["milestone", "strategy", "x"]).reset_index(drop=True)


def draw(data: pd.DataFrame, out: Path) -> None:
    """The three panels, one colour per strategy."""
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.6))
    for n, (strategy, rows) in enumerate(data.groupby("strategy")):
        colour = f"C{n}"
        for ax, milestone in zip(axes[:2], MILESTONES, strict=True):
            mine = rows[rows["milestone"] == milestone]
            draw_milestone(ax, mine["x"], mine, str(strategy), ("-", colour), TOP)
        once = rows[rows["milestone"] == MILESTONES[0]]
        if strategy == "role_based":
            draw_mean(axes[2], once["x"], once, "meetings_kept", "role_based: meetings kept",
                      ("-", colour))  # fmt: skip
        waiting = once.assign(waiting_robot_steps=once["waiting_robot_steps"] / 100)
        ci = [tuple(v / 100 for v in pair) for pair in once["waiting_robot_steps_ci"]]
        waiting["waiting_robot_steps_ci"] = ci
        draw_mean(axes[2], once["x"], waiting, "waiting_robot_steps",
                  f"{strategy}: robot-steps held still / 100", ("--", colour))  # fmt: skip
    axes[0].set(title="steps to 90 % known at base (Kaplan-Meier median, 95 %)", ylabel="steps")
    axes[1].set(title="steps to 90 % explored (Kaplan-Meier median, 95 %)", ylabel="steps")
    axes[2].set(title="meetings kept; robot-steps held still", ylabel="count")
    for ax in axes:
        ax.set_xticks(range(len(ARMS)), ARMS)
    save(fig, axes, "clock of every robot", out)


def report(runs: pd.DataFrame) -> None:
    """The paired difference in differences of each clock (module docstring)."""
    runs = runs[runs["status"] == "done"].copy()
    runs["clock"] = runs[CLOCK].map(clock_label)
    steps = runs.pivot_table(index="seed", columns=[STRATEGY, "clock"], values=MILESTONES[0])
    steps = steps.reindex(columns=pd.MultiIndex.from_product([["role_based", "frontier"], ARMS]))
    print(f"\n{MILESTONES[0]}: (role_based - its no-clock arm) - (frontier - its no-clock arm)")
    for clock in ARMS[1:]:
        cost = {s: steps[(s, clock)] - steps[(s, "none")] for s in ("role_based", "frontier")}
        diff = (cost["role_based"] - cost["frontier"]).to_numpy(dtype=float)
        censored = int(np.isnan(diff).sum())
        if censored:
            print(f"  {clock:9s}: not computed, {censored} of {len(diff)} seeds censored")
            continue
        test = stats.ttest_1samp(diff, 0.0)
        low, high = test.confidence_interval(0.95)
        interval = f"[{low:+.1f}, {high:+.1f}]"
        print(f"  {clock:9s}: {diff.mean():+.1f} steps {interval}, p = {test.pvalue:.2g}")


if __name__ == "__main__":
    run_tool(__doc__, "clock_delay.png", table, draw, report)
