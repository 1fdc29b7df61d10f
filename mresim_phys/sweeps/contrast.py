"""The robustness contrast (sweeps, compare): is strategy A more robust than strategy B?

"More robust" is an interaction: A degrades less than B as robots fail. For a fault axis
(``failures`` or a ``faults.*`` path), a baseline level (the reference arm's, e.g. 0
failures), a level ``k`` and two groups A and B of the other ``--by`` columns (the
strategies), each seed gives one *contrast*:

    (A at k - A at baseline) - (B at k - B at baseline)

the paired difference of the two degradations, all four runs sharing the seed and every
other axis value (common random numbers). Over the seeds: the mean contrast with its 95 %
Student-t interval and two-sided paired t-test (``scipy.stats.ttest_1samp``), the
Wilcoxon signed-rank p as a check that needs no normality, the effect size Cohen's d_z
(mean / standard deviation of the contrasts), and the seeds a paired t-test would need to
detect a contrast of a given size at 80 % power and alpha 0.05 (``statsmodels``
``TTestPower``; the size is ``--detect`` or, by default, the observed mean contrast).

A steps-to-threshold metric a run never reached has no value: a seed with such a run in
any of its four arms is censored, and a contrast with censored seeds is *not estimated*
(its row says how many seeds were censored). Choose a metric every run has, such as
``auc_known_at_base``, the area under the base's knowledge curve.

Whether a positive contrast means "A is more robust" depends on the metric's direction:
:func:`higher_is_better`. The verdict is stated only when the interval excludes 0.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from itertools import combinations
from typing import Any

import numpy as np
import pandas as pd
from scipy import stats

from mresim_phys.sweeps.stats import same_key
from mresim_phys.sweeps.survival import is_time_to_event
from mresim_phys.sweeps.worker import DONE

ALPHA = 0.05
POWER = 0.8
MOST_SEEDS = 10_000
LOWER_IS_BETTER = ("steps_to_", "idle_", "stuck_", "robots_idle", "base_deficit", "failed_")


def higher_is_better(metric: str) -> bool:
    """Whether a larger value of ``metric`` is better (areas, fractions) or worse (steps,
    idle robots).

    >>> higher_is_better("auc_known_at_base"), higher_is_better("steps_to_explored_90")
    (True, False)
    """
    name = metric.removeprefix("diff_")
    return not any(name.startswith(p) for p in LOWER_IS_BETTER)


@dataclass(frozen=True)
class Contrast:
    """A against B at one fault level: the per-seed difference of their degradations."""

    a: str
    b: str
    level: Any
    baseline: Any
    seeds: int
    censored: int
    mean: float
    ci_low: float
    ci_high: float
    t_p: float
    wilcoxon_p: float
    effect: float
    detect: float
    seeds_needed: float
    values: tuple[float, ...] = ()

    @property
    def estimated(self) -> bool:
        """Whether the contrast has a value: two or more seeds and none censored."""
        return self.censored == 0 and self.seeds >= 2

    def verdict(self, better_high: bool) -> str:
        """ "A is more robust than B", the reverse, or "no difference shown"."""
        if not self.estimated or math.isnan(self.ci_low):
            return "not estimated"
        if self.ci_low <= 0 <= self.ci_high:
            return "no difference shown (the interval holds 0)"
        a_better = (self.mean > 0) == better_high
        first, second = (self.a, self.b) if a_better else (self.b, self.a)
        return f"{first} is more robust than {second}"


@dataclass(frozen=True)
class Design:
    """How runs form the contrast: the fault axis, the other ``by`` columns (groups),
    the pairing keys (scenario, seed, other axes) and the baseline fault level."""

    axis: str
    groups: list[str]
    pair_keys: list[str]
    baseline: Any


Cells = dict[tuple[Any, ...], pd.Series]


def cells(runs: pd.DataFrame, metric: str, design: Design) -> Cells:
    """Each (group..., fault level)'s values of ``metric`` indexed by the pairing keys
    (NaN: a threshold never reached)."""
    values = pd.to_numeric(runs[metric], errors="coerce").to_numpy(float)
    index = pd.MultiIndex.from_frame(runs[design.pair_keys])
    groups = runs.groupby([*design.groups, design.axis], sort=False, dropna=False).indices
    return {
        key if isinstance(key, tuple) else (key,): pd.Series(values[rows], index=index[rows])
        for key, rows in groups.items()
    }


def cell(found: Cells, key: tuple[Any, ...]) -> pd.Series:
    """One cell by its key (NaN matching NaN); empty when no run has it."""
    hit = next((v for k, v in found.items() if same_key(k, key)), None)
    return hit if hit is not None else pd.Series(dtype=float)


def per_seed(
    found: Cells, design: Design, a: tuple[Any, ...], b: tuple[Any, ...], level: Any
) -> pd.DataFrame:
    """The four arms' values per pairing key: a_k, a_0, b_k, b_0 (inner join: a seed with a
    failed run in any of the four arms has no contrast)."""
    parts = {
        "a_k": cell(found, (*a, level)),
        "a_0": cell(found, (*a, design.baseline)),
        "b_k": cell(found, (*b, level)),
        "b_0": cell(found, (*b, design.baseline)),
    }
    if any(not len(part) for part in parts.values()):
        empty: pd.DataFrame = pd.DataFrame(columns=list(parts), dtype=float)
        return empty
    table: pd.DataFrame = pd.concat(parts, axis=1, join="inner")
    return table


def seeds_needed(effect: float) -> float:
    """The fewest seeds (2 to :data:`MOST_SEEDS`) with which a two-sided paired t-test
    detects ``effect`` (d_z) at 80 % power and alpha 0.05 (``statsmodels`` ``TTestPower``);
    inf when more are needed, NaN for no effect."""
    if not math.isfinite(effect) or effect == 0:
        return math.nan
    from statsmodels.stats.power import TTestPower

    seeds = np.arange(2, MOST_SEEDS + 1)
    power = TTestPower().power(effect_size=abs(effect), nobs=seeds, alpha=ALPHA)
    enough = np.flatnonzero(np.asarray(power) >= POWER)
    return float(seeds[enough[0]]) if len(enough) else math.inf


def summarise(
    a: str, b: str, level: Any, baseline: Any, table: pd.DataFrame, detect: float | None
) -> Contrast:
    """The contrast's figures from the per-seed table."""
    values = ((table["a_k"] - table["a_0"]) - (table["b_k"] - table["b_0"])).to_numpy(float)
    censored_seeds = int(np.isnan(values).sum())
    nan = math.nan
    if censored_seeds or len(values) < 2:
        return Contrast(a, b, level, baseline, len(values), censored_seeds, *(nan,) * 8)
    mean, sd = float(values.mean()), float(values.std(ddof=1))
    if sd == 0:  # every seed the same contrast: no spread to test against
        return Contrast(
            a,
            b,
            level,
            baseline,
            len(values),
            0,
            mean,
            mean,
            mean,
            nan,
            nan,
            nan,
            nan,
            nan,
            tuple(values),
        )
    test = stats.ttest_1samp(values, 0.0)
    interval = test.confidence_interval(1 - ALPHA)
    wilcoxon_p = paired_wilcoxon(values)
    size = abs(mean) if detect is None else abs(detect)
    return Contrast(
        a,
        b,
        level,
        baseline,
        len(values),
        0,
        mean,
        float(interval.low),
        float(interval.high),
        float(test.pvalue),
        wilcoxon_p,
        mean / sd,
        size,
        seeds_needed(size / sd),
        tuple(values),
    )


def paired_wilcoxon(values: np.ndarray) -> float:
    """The two-sided Wilcoxon signed-rank p of the contrasts (1 when all are 0)."""
    if not np.any(values != 0):
        return 1.0
    with warnings.catch_warnings():  # ties force the normal approximation; that p is used
        warnings.simplefilter("ignore")
        return float(stats.wilcoxon(values, zero_method="wilcox").pvalue)


def contrasts(
    runs: pd.DataFrame, metric: str, design: Design, label: Any, detect: float | None = None
) -> list[Contrast]:
    """Every pair of groups (in sweep order, the first group as A of its pairs) at every
    fault level other than the baseline. ``label`` names a group tuple."""
    done = runs[runs["status"] == DONE]
    keys = design.groups or ["scenario"]
    groups = [
        k if isinstance(k, tuple) else (k,) for k, _ in done.groupby(keys, sort=False, dropna=False)
    ]
    levels = [
        v
        for v in dict.fromkeys(done[design.axis].tolist())
        if not same_key((v,), (design.baseline,))
    ]
    found, out = cells(done, metric, design), []
    for a, b in combinations(groups, 2):
        for level in levels:
            table = per_seed(found, design, a, b, level)
            out.append(summarise(label(a), label(b), level, design.baseline, table, detect))
    return out


def time_to_event_note(metric: str) -> str:
    """Why a steps-to metric's contrast may be missing: what to use instead."""
    if not is_time_to_event(metric):
        return ""
    return (
        " A seed whose run never reached the threshold in any of the four arms is censored"
        " and the contrast is not estimated over it; auc_known_at_base has a value for"
        " every run."
    )
