"""Censored times to a threshold (sweeps, compare): Kaplan-Meier medians and log-rank tests.

A ``steps_to_*`` metric is a time to an event. A run that never reached the threshold is
*right-censored*: all we know is that it needed more than it had. Such a run is never given
a number. A run cut by the step cap, a goal rule or an interruption is censored at its
last step (``steps``). A run that stopped because its team could do no more (stop reason
``all_done``: every robot failed, or done and parked; ``stalled``: no progress) would
never have reached the threshold: it is censored at the sweep's longest run (the
*horizon*), so it stays at risk past every time any run reached it instead of leaving the
risk set early as if it might have reached it soon after.

Per arm: the runs, how many reached the threshold and the share that did not, and the
Kaplan-Meier median with its 95 % interval (``scipy.stats.ecdf`` on
``scipy.stats.CensoredData``; the interval is where the pointwise log-log band of the
survival curve crosses 0.5, as R's ``survfit`` reports it). A median the curve never
falls to is *not reached*; an interval end the band never crosses is *not estimable*
(shown as ``>`` the longest run). Arms are compared with the reference arm by the
two-sided log-rank test (``scipy.stats.logrank``), which uses the censored runs as they
are.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd
from scipy import stats

from mresim_phys.sweeps.worker import DONE

CONFIDENCE = 0.95
FROZEN = ("all_done", "stalled")  # stop reasons after which a run's fractions cannot grow


def is_time_to_event(metric: str) -> bool:
    """Whether ``metric`` is a steps-to-threshold metric (censored when never reached).

    >>> is_time_to_event("steps_to_known_at_base_90"), is_time_to_event("auc_explored")
    (True, False)
    """
    return metric.startswith("steps_to_")


@dataclass(frozen=True)
class ArmSurvival:
    """One arm's Kaplan-Meier figures for one steps-to-threshold metric."""

    arm: str
    n: int
    reached: int
    median: float  # inf: the curve never falls to 0.5 (median not reached)
    ci_low: float
    ci_high: float  # inf: the band never crosses 0.5 (not estimable)
    longest: float  # the longest run's steps: a "> longest" bound
    failed: int = 0

    @property
    def not_reached(self) -> int:
        """Runs that never reached the threshold (censored)."""
        return self.n - self.reached

    @property
    def share_not_reached(self) -> float:
        """The share of the arm's done runs that never reached the threshold."""
        return self.not_reached / self.n if self.n else math.nan


@dataclass(frozen=True)
class LogRank:
    """An arm against the reference arm by the log-rank test."""

    arm: str
    runs: int
    reference_runs: int
    reached: int
    reference_reached: int
    statistic: float
    p_value: float


def horizon_of(runs: pd.DataFrame) -> float:
    """The longest done run's steps: where runs that could do no more are censored."""
    done = runs[runs["status"] == DONE] if "status" in runs.columns else runs
    return float(pd.to_numeric(done["steps"], errors="coerce").max())


def event_times(
    runs: pd.DataFrame, metric: str, horizon: float | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """(times reached, censoring times) of the runs: a run that never reached ``metric``'s
    threshold is censored at its last step, or at ``horizon`` (default the runs' longest)
    when it stopped because its team could do no more (:data:`FROZEN`)."""
    values = pd.to_numeric(runs[metric], errors="coerce").astype(float).to_numpy()
    steps = pd.to_numeric(runs["steps"], errors="coerce").astype(float).to_numpy()
    if "stop_reason" in runs.columns:
        frozen = runs["stop_reason"].isin(FROZEN).to_numpy()
        steps = np.where(frozen, horizon_of(runs) if horizon is None else horizon, steps)
    reached = ~np.isnan(values)
    return values[reached], steps[~reached]


def censored(runs: pd.DataFrame, metric: str, horizon: float | None = None) -> stats.CensoredData:
    """The runs' times to ``metric``'s threshold as censored data (:func:`event_times`)."""
    reached, cut = event_times(runs, metric, horizon)
    return stats.CensoredData(uncensored=reached, right=cut)


def first_below(times: np.ndarray, curve: np.ndarray, level: float = 0.5) -> float:
    """The first time at which ``curve`` is at or below ``level`` (inf if never).

    >>> first_below(np.array([1.0, 2.0, 3.0]), np.array([0.9, 0.5, 0.2]))
    2.0
    """
    below = np.flatnonzero(curve <= level + 1e-12)
    return float(times[below[0]]) if len(below) else math.inf


def km_median(data: stats.CensoredData) -> tuple[float, float, float]:
    """(median, low, high): the Kaplan-Meier median and its 95 % interval (inf: never)."""
    if data.num_censored() == len(data):  # no event: the curve stays at 1
        return math.inf, math.inf, math.inf
    curve = stats.ecdf(data).sf
    with np.errstate(divide="ignore", invalid="ignore"), warnings.catch_warnings():
        # the log-log band is undefined where the curve is 0 or 1: NaN there, handled below
        warnings.simplefilter("ignore", category=RuntimeWarning)
        band: Any = curve.confidence_interval(CONFIDENCE, method="log-log")
    times = curve.quantiles
    return (
        first_below(times, curve.probabilities),
        first_below(times, np.nan_to_num(band.low.probabilities, nan=0.0)),
        first_below(times, np.nan_to_num(band.high.probabilities, nan=1.0)),
    )


def arm_survival(
    label: str, all_runs: pd.DataFrame, metric: str, horizon: float | None = None
) -> ArmSurvival:
    """An arm's runs, reached count, Kaplan-Meier median and interval, failed count."""
    runs = all_runs[all_runs["status"] == DONE]
    failed = len(all_runs) - len(runs)
    if not len(runs):
        return ArmSurvival(label, 0, 0, math.nan, math.nan, math.nan, math.nan, failed)
    data = censored(runs, metric, horizon)
    median, low, high = km_median(data)
    longest = float(pd.to_numeric(runs["steps"], errors="coerce").max())
    reached = len(data) - data.num_censored()
    return ArmSurvival(label, len(data), reached, median, low, high, longest, failed)


def log_rank(
    label: str,
    runs: pd.DataFrame,
    reference: pd.DataFrame,
    metric: str,
    horizon: float | None = None,
) -> LogRank:
    """``runs`` against ``reference`` by the two-sided log-rank test (NaN when neither arm
    has a run that reached the threshold, or one arm is empty)."""
    if horizon is None:
        horizon = max(horizon_of(runs), horizon_of(reference))
    mine, theirs = censored(runs, metric, horizon), censored(reference, metric, horizon)
    events = [len(d) - d.num_censored() for d in (mine, theirs)]
    statistic = p_value = math.nan
    if len(mine) and len(theirs) and sum(events):
        with warnings.catch_warnings():  # a zero variance gives NaN, reported as such
            warnings.simplefilter("ignore", category=RuntimeWarning)
            result = stats.logrank(mine, theirs, alternative="two-sided")
        statistic, p_value = float(result.statistic), float(result.pvalue)
    return LogRank(label, len(mine), len(theirs), events[0], events[1], statistic, p_value)
