"""Sweep statistics (sweeps, compare): per-arm figures and paired differences.

Arms are the groups of ``runs.parquet`` by the ``--by`` columns. Per arm and metric that
every run has (areas, fractions, counts): runs, mean, median and the 95 % confidence
interval of the mean (Student's t). A steps-to-threshold metric is a time to an event,
censored when never reached: it has Kaplan-Meier medians and log-rank tests instead
(``sweeps/survival.py``) and is never averaged. Paired differences
against the reference arm use the common random numbers: a run is paired with the
reference run of the same base scenario, seed and other axis values, the difference is
run minus reference, tested by the Wilcoxon signed-rank test (``scipy.stats.wilcoxon``,
two-sided; pairs with no difference are dropped, as Wilcoxon's original test does), with
the matched-pairs rank-biserial correlation as its effect size: (W+ - W-) / (W+ + W-),
from -1 (every run below its reference) to +1 (every run above). Failed runs have no
figures; they are listed in the report, never silently dropped.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy import stats

from mresim_phys.sweeps.survival import (
    ArmSurvival,
    LogRank,
    arm_survival,
    horizon_of,
    is_time_to_event,
    log_rank,
)
from mresim_phys.sweeps.worker import DONE

Key = tuple[object, ...]


@dataclass(frozen=True)
class ArmFigures:
    """One arm's figures for one metric."""

    arm: str
    n: int
    mean: float
    median: float
    ci_low: float
    ci_high: float
    failed: int = 0


@dataclass(frozen=True)
class Paired:
    """An arm against the reference arm, run by run."""

    arm: str
    pairs: int
    mean_diff: float
    median_diff: float
    statistic: float
    p_value: float
    effect: float


def metric_values(runs: pd.DataFrame, metric: str) -> pd.Series:
    """``metric`` of the runs as numbers (a missing value stays NaN: never imputed)."""
    values: pd.Series = pd.to_numeric(runs[metric], errors="coerce").astype(float)
    return values


def mean_ci(values: np.ndarray) -> tuple[float, float]:
    """The 95 % Student-t interval of the mean (NaN for fewer than two values)."""
    n = len(values)
    if n < 2:
        return math.nan, math.nan
    mean, sem = float(np.mean(values)), float(np.std(values, ddof=1)) / math.sqrt(n)
    half = float(stats.t.ppf(0.975, n - 1)) * sem
    return mean - half, mean + half


def arm_figures(label: str, all_runs: pd.DataFrame, metric: str) -> ArmFigures:
    """An arm's n, mean, median, 95 % CI and failed count (runs without a value of
    ``metric`` are left out of n)."""
    runs = all_runs[all_runs["status"] == DONE]
    failed = len(all_runs) - len(runs)
    values = metric_values(runs, metric).dropna().to_numpy()
    low, high = mean_ci(values)
    mean = float(np.mean(values)) if len(values) else math.nan
    median = float(np.median(values)) if len(values) else math.nan
    return ArmFigures(label, len(values), mean, median, low, high, failed)


def rank_biserial(diffs: np.ndarray) -> float:
    """Matched-pairs rank-biserial correlation of the non-zero differences.

    >>> rank_biserial(np.array([1.0, 2.0, -0.5]))
    0.6666666666666666
    """
    nonzero = diffs[diffs != 0]
    if not len(nonzero):
        return 0.0
    ranks = stats.rankdata(np.abs(nonzero))
    plus, minus = ranks[nonzero > 0].sum(), ranks[nonzero < 0].sum()
    return float((plus - minus) / (plus + minus))


def wilcoxon(diffs: np.ndarray) -> tuple[float, float]:
    """(W, two-sided p) of the Wilcoxon signed-rank test; (0, 1) when every pair ties."""
    if not np.any(diffs != 0):
        return 0.0, 1.0
    with warnings.catch_warnings():
        # scipy warns when ties or zeros force the normal approximation; the p value it
        # returns is the one we report
        warnings.simplefilter("ignore", category=UserWarning)
        warnings.simplefilter("ignore", category=RuntimeWarning)
        result = stats.wilcoxon(diffs, zero_method="wilcox", alternative="two-sided")
    return float(result.statistic), float(result.pvalue)


def paired(
    label: str, runs: pd.DataFrame, reference: pd.DataFrame, metric: str, keys: list[str]
) -> Paired:
    """``runs`` against ``reference``, paired on ``keys`` (scenario, seed, other axes)."""
    left = runs[keys].assign(value=metric_values(runs, metric).to_numpy())
    right = reference[keys].assign(ref=metric_values(reference, metric).to_numpy())
    both = left.merge(right, on=keys, how="inner").dropna(subset=["value", "ref"])
    diffs = (both["value"] - both["ref"]).to_numpy(dtype=float)
    if not len(diffs):
        return Paired(label, 0, math.nan, math.nan, math.nan, math.nan, math.nan)
    statistic, p_value = wilcoxon(diffs)
    return Paired(
        label,
        len(diffs),
        float(np.mean(diffs)),
        float(np.median(diffs)),
        statistic,
        p_value,
        rank_biserial(diffs),
    )


@dataclass(frozen=True)
class Grouping:
    """How a sweep's runs form arms: the ``by`` columns and the pairing keys."""

    by: list[str]
    pair_keys: list[str]
    reference: Key

    def label(self, key: Key) -> str:
        """``strategy=frontier, count=4`` for an arm key."""
        return ", ".join(f"{c.rsplit('.', 1)[-1]}={v}" for c, v in zip(self.by, key, strict=True))


def arm_groups(
    runs: pd.DataFrame, grouping: Grouping, done: bool = True
) -> list[tuple[Key, pd.DataFrame]]:
    """The done runs (or all runs) of each arm, arms in the order of the sweep."""
    chosen = runs[runs["status"] == DONE] if done else runs
    groups = chosen.groupby(grouping.by, sort=False, dropna=False)
    return [(k if isinstance(k, tuple) else (k,), g) for k, g in groups]


Arms = list[ArmFigures] | list[ArmSurvival]
Pairs = list[Paired] | list[LogRank]


def compare_metric(runs: pd.DataFrame, metric: str, grouping: Grouping) -> tuple[Arms, Pairs]:
    """Per-arm figures and the comparisons with the reference arm for ``metric``: for a
    steps-to-threshold metric Kaplan-Meier figures and log-rank tests, else means and
    paired Wilcoxon tests."""
    every = arm_groups(runs, grouping, False)
    groups = arm_groups(runs, grouping)
    reference = next((g for k, g in groups if same_key(k, grouping.reference)), None)
    others = [(grouping.label(k), g) for k, g in groups if not same_key(k, grouping.reference)]
    if is_time_to_event(metric):
        end = horizon_of(runs)
        survival = [arm_survival(grouping.label(k), g, metric, end) for k, g in every]
        ranks = (
            [] if reference is None else [log_rank(n, g, reference, metric, end) for n, g in others]
        )
        return survival, ranks
    figures = [arm_figures(grouping.label(k), g, metric) for k, g in every]
    pairs = []
    if reference is not None:
        pairs = [paired(n, g, reference, metric, grouping.pair_keys) for n, g in others]
    return figures, pairs


def same_key(a: Key, b: Key) -> bool:
    """Equal arm keys (NaN equals NaN: an axis value switched off)."""
    return len(a) == len(b) and all(
        x == y or (x != x and y != y) for x, y in zip(a, b, strict=True)
    )
