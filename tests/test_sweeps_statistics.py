"""The sweep statistics validated on synthetic data with a known answer: Kaplan-Meier
medians cover the true median, the log-rank test holds its size, a robustness contrast of 0
gives uniform p values, a known contrast is found at the power the seed count was chosen
for, and a censored time is never given a number."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from mresim_phys.sweeps.contrast import Contrast, Design, contrasts, seeds_needed
from mresim_phys.sweeps.stats import Grouping, compare_metric
from mresim_phys.sweeps.survival import (
    ArmSurvival,
    arm_survival,
    event_times,
    km_median,
    log_rank,
)

DRAWS = 400
METRIC = "steps_to_explored_90"


def times_frame(rng: np.random.Generator, n: int, scale: float, cap: float) -> pd.DataFrame:
    """``n`` runs whose times are exponential with ``scale``, cut at ``cap`` (censored: no
    value) or earlier at a uniform stop (a run stopped by a rule)."""
    times = rng.exponential(scale, n)
    stops = np.minimum(rng.uniform(0.5 * cap, 2 * cap, n), cap)
    reached = times <= stops
    return pd.DataFrame(
        {
            METRIC: np.where(reached, np.round(times, 3), np.nan),
            "steps": np.where(reached, cap, np.round(stops, 3)),
            "status": "done",
        }
    )


def test_kaplan_meier_median_of_a_textbook_sample() -> None:
    data = stats.CensoredData(uncensored=[10, 20, 30, 40, 50], right=[60, 60])
    median, low, high = km_median(data)
    assert median == 40  # S drops to 3/7 at 40
    assert low == 10 and math.isinf(high)  # the log-log band never falls to 0.5 above


def test_an_arm_that_never_reached_has_no_median() -> None:
    runs = pd.DataFrame({METRIC: [np.nan] * 4, "steps": [300] * 4, "status": "done"})
    arm = arm_survival("a", runs, METRIC)
    assert (arm.n, arm.reached, arm.share_not_reached) == (4, 0, 1.0)
    assert math.isinf(arm.median) and arm.longest == 300


def test_kaplan_meier_interval_covers_the_true_median() -> None:
    rng = np.random.default_rng(29)
    scale, truth, covered = 100.0, 100.0 * math.log(2), 0
    for _ in range(DRAWS):
        _, low, high = km_median(arm_data(times_frame(rng, 40, scale, 250.0)))
        covered += low <= truth <= high
    share = covered / DRAWS
    assert 0.91 <= share <= 0.985, share  # nominal 95 %; binomial spread over 400 draws


def arm_data(frame: pd.DataFrame) -> stats.CensoredData:
    values = frame[METRIC].to_numpy()
    reached = ~np.isnan(values)
    return stats.CensoredData(uncensored=values[reached], right=frame["steps"].to_numpy()[~reached])


def test_log_rank_holds_its_size_and_finds_a_real_difference() -> None:
    rng = np.random.default_rng(7)
    null = [
        log_rank("a", times_frame(rng, 30, 100, 200), times_frame(rng, 30, 100, 200), METRIC)
        for _ in range(DRAWS)
    ]
    rejected = np.mean([r.p_value < 0.05 for r in null])
    assert 0.025 <= rejected <= 0.08, rejected
    assert stats.kstest([r.p_value for r in null], "uniform").pvalue > 0.001
    shifted = [
        log_rank("a", times_frame(rng, 30, 50, 200), times_frame(rng, 30, 200, 200), METRIC)
        for _ in range(100)
    ]
    assert np.mean([r.p_value < 0.05 for r in shifted]) > 0.9


def robustness_runs(
    rng: np.random.Generator, seeds: int, contrast: float, sd: float = 1.0
) -> pd.DataFrame:
    """A synthetic robustness sweep: strategies A and B, 0 and 1 failure, ``seeds`` seeds.
    Each seed has its own level (common random numbers) and failure hurts both; A loses
    ``contrast`` less than B (the interaction), plus noise of ``sd`` per contrast."""
    rows = []
    for seed in range(seeds):
        base = rng.normal(100, 10)
        noise = rng.normal(0, sd / 2, 4)  # four runs: the contrast's SD is sd
        for i, (strategy, k) in enumerate((s, f) for s in ("A", "B") for f in (0, 1)):
            loss = (-5.0 + contrast if strategy == "A" else -5.0) if k else 0.0
            value = base + (3.0 if strategy == "A" else 0.0) + loss + noise[i]
            rows.append(
                {
                    "scenario": "s",
                    "seed": seed,
                    "team.strategy": strategy,
                    "failures": k,
                    "status": "done",
                    "auc_known_at_base": value,
                }
            )
    return pd.DataFrame(rows)


DESIGN = Design("failures", ["team.strategy"], ["scenario", "seed"], 0)


def contrast_of(runs: pd.DataFrame, detect: float | None = None) -> Contrast:
    (found,) = contrasts(runs, "auc_known_at_base", DESIGN, lambda g: str(g[0]), detect)
    return found


def test_a_contrast_of_zero_gives_uniform_p_values() -> None:
    rng = np.random.default_rng(11)
    found = [contrast_of(robustness_runs(rng, 12, 0.0)) for _ in range(DRAWS)]
    p_values = np.array([c.t_p for c in found])
    assert stats.kstest(p_values, "uniform").pvalue > 0.001
    assert 0.025 <= np.mean(p_values < 0.05) <= 0.08
    covered = np.mean([c.ci_low <= 0 <= c.ci_high for c in found])
    assert 0.92 <= covered <= 0.975


def test_a_known_contrast_is_found_at_the_stated_power() -> None:
    rng = np.random.default_rng(3)
    shift, sd = 1.0, 1.6
    seeds = int(seeds_needed(shift / sd))
    assert seeds == needed_by_search(shift / sd)  # statsmodels agrees with scipy's noncentral t
    found = [contrast_of(robustness_runs(rng, seeds, shift, sd)) for _ in range(DRAWS)]
    power = np.mean([c.t_p < 0.05 and c.mean > 0 for c in found])
    assert 0.74 <= power <= 0.9, (seeds, power)
    first = found[0]
    assert first.verdict(True) in (
        "A is more robust than B",
        "no difference shown (the interval holds 0)",
    )


def needed_by_search(effect: float) -> int:
    """The least n whose two-sided one-sample t-test has power >= 0.8 at alpha 0.05."""
    for n in range(2, 1000):
        crit = stats.t.isf(0.025, n - 1)
        nc = effect * math.sqrt(n)
        power = stats.nct.sf(crit, n - 1, nc) + stats.nct.cdf(-crit, n - 1, nc)
        if power >= 0.8:
            return n
    raise AssertionError("no n")


def test_a_seed_with_a_censored_run_makes_the_contrast_not_estimated() -> None:
    runs = robustness_runs(np.random.default_rng(1), 8, 1.0).rename(
        columns={"auc_known_at_base": METRIC}
    )
    runs["steps"] = 500
    runs.loc[5, METRIC] = np.nan  # one run never reached the threshold
    (found,) = contrasts(runs, METRIC, DESIGN, lambda g: str(g[0]))
    assert (found.seeds, found.censored) == (8, 1) and not found.estimated
    assert math.isnan(found.mean) and found.verdict(False) == "not estimated"


def test_a_time_to_threshold_is_never_averaged() -> None:
    """compare gives Kaplan-Meier figures and log-rank tests for a steps-to metric: no mean,
    and no number for a run that never reached it."""
    rng = np.random.default_rng(5)
    runs = pd.concat(
        [times_frame(rng, 20, 100, 120).assign(arm=a, scenario="s", seed=range(20)) for a in "xy"],
        ignore_index=True,
    )
    grouping = Grouping(["arm"], ["scenario", "seed"], ("x",))
    arms, pairs = compare_metric(runs, METRIC, grouping)
    assert all(isinstance(a, ArmSurvival) for a in arms)
    first = arms[0]
    assert isinstance(first, ArmSurvival)
    mine = runs[runs["arm"] == "x"]
    assert first.not_reached == mine[METRIC].isna().sum() > 0
    assert first.median == km_median(arm_data(mine))[0]
    assert not hasattr(first, "mean")
    assert pairs[0].p_value == pytest.approx(  # type: ignore[union-attr]
        stats.logrank(arm_data(runs[runs["arm"] == "y"]), arm_data(mine)).pvalue
    )


def test_a_run_whose_team_could_do_no_more_stays_at_risk_to_the_horizon() -> None:
    """Two runs stopped all_done at step 20 without reaching the threshold would never
    have reached it: censored at the sweep's longest run, not at 20, which would drop them
    from the risk set and make the arm look faster (median 40 instead of 50)."""
    runs = pd.DataFrame(
        {
            METRIC: [30, 40, 50, np.nan, np.nan],
            "steps": [300, 300, 300, 20, 20],
            "stop_reason": ["steps", "steps", "steps", "all_done", "stalled"],
            "status": "done",
        }
    )
    reached, cut = event_times(runs, METRIC, 300.0)
    assert list(reached) == [30, 40, 50] and list(cut) == [300, 300]
    assert arm_survival("a", runs, METRIC).median == 50
    as_if_cut = runs.assign(stop_reason="steps")  # cut by the cap at 20: censored there
    assert arm_survival("a", as_if_cut, METRIC).median == 40
