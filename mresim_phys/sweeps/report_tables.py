"""Sweep report tables (sweeps, compare): a metric's figures as rows of text.

Means and their intervals for metrics every run has; Kaplan-Meier medians, the share not
reached and log-rank tests for steps-to-threshold metrics (censored runs are never given a
number: ``sweeps/survival.py``); the robustness contrasts (``sweeps/contrast.py``).
Numbers are shown with four significant digits.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from mresim_phys.sweeps.contrast import MOST_SEEDS, Contrast, higher_is_better
from mresim_phys.sweeps.stats import ArmFigures, Arms, Paired, Pairs
from mresim_phys.sweeps.survival import ArmSurvival, LogRank, is_time_to_event

Table = list[list[str]]
ARM_HEAD = ["arm", "runs", "mean", "median", "95 % CI", "failed"]
PAIR_HEAD = ["arm", "pairs", "mean diff", "median diff", "Wilcoxon W", "p", "effect size r"]
SURVIVAL_HEAD = [
    "arm",
    "runs",
    "reached",
    "not reached",
    "share not reached",
    "Kaplan-Meier median",
    "95 % CI",
    "failed",
]
LOGRANK_HEAD = [
    "arm",
    "runs",
    "reached",
    "reference runs",
    "reference reached",
    "log-rank z",
    "p",
]
CONTRAST_HEAD = [
    "A",
    "B",
    "level",
    "seeds",
    "censored seeds",
    "mean contrast",
    "95 % CI",
    "t-test p",
    "Wilcoxon p",
    "effect size d_z",
    "seeds for 80 % power",
    "verdict",
]


@dataclass(frozen=True)
class Section:
    """One metric's figures: per arm, against the reference arm, and the robustness
    contrasts (when the sweep has a fault axis)."""

    metric: str
    arms: Arms
    pairs: Pairs
    contrasts: list[Contrast] = field(default_factory=list)


def num(value: float) -> str:
    """A number with four significant digits ('-' for NaN).

    >>> num(1234.567), num(0.012345), num(float("nan"))
    ('1235', '0.01235', '-')
    """
    return "-" if math.isnan(value) else f"{value:.4g}"


def bound(value: float, longest: float) -> str:
    """An interval end of a Kaplan-Meier median; inf: the band never crosses 0.5.

    >>> bound(math.inf, 300.0), bound(120.0, 300.0)
    ('not estimable (> 300)', '120')
    """
    return f"not estimable (> {num(longest)})" if math.isinf(value) else num(value)


def survival_row(a: ArmSurvival) -> list[str]:
    """One arm's Kaplan-Meier row."""
    median = f"not reached (> {num(a.longest)})" if math.isinf(a.median) else num(a.median)
    share = "-" if math.isnan(a.share_not_reached) else f"{a.share_not_reached:.0%}"
    interval = f"[{bound(a.ci_low, a.longest)}, {bound(a.ci_high, a.longest)}]"
    if not a.n:
        median = interval = "-"
    return [
        a.arm,
        str(a.n),
        str(a.reached),
        str(a.not_reached),
        share,
        median,
        interval,
        str(a.failed),
    ]


def arm_row(a: ArmFigures) -> list[str]:
    """One arm's row of means."""
    interval = f"[{num(a.ci_low)}, {num(a.ci_high)}]"
    return [a.arm, str(a.n), num(a.mean), num(a.median), interval, str(a.failed)]


def arm_table(section: Section) -> tuple[list[str], Table]:
    """The per-arm table (head, rows): Kaplan-Meier rows for a steps-to-threshold metric."""
    rows = [survival_row(a) if isinstance(a, ArmSurvival) else arm_row(a) for a in section.arms]
    return (SURVIVAL_HEAD if is_time_to_event(section.metric) else ARM_HEAD), rows


def pair_row(p: Paired | LogRank) -> list[str]:
    """One comparison with the reference arm: a log-rank test or paired differences."""
    if isinstance(p, LogRank):
        return [
            p.arm,
            str(p.runs),
            str(p.reached),
            str(p.reference_runs),
            str(p.reference_reached),
            num(p.statistic),
            num(p.p_value),
        ]
    return [
        p.arm,
        str(p.pairs),
        num(p.mean_diff),
        num(p.median_diff),
        num(p.statistic),
        num(p.p_value),
        num(p.effect),
    ]


def pair_table(section: Section) -> tuple[list[str], Table]:
    """The table against the reference arm (head, rows): log-rank or paired Wilcoxon."""
    head = LOGRANK_HEAD if is_time_to_event(section.metric) else PAIR_HEAD
    return head, [pair_row(p) for p in section.pairs]


def contrast_row(c: Contrast, metric: str) -> list[str]:
    """One robustness contrast's row."""
    level = f"{c.level} vs {c.baseline}"
    interval = f"[{num(c.ci_low)}, {num(c.ci_high)}]" if c.estimated else "-"
    return [
        c.a,
        c.b,
        level,
        str(c.seeds),
        str(c.censored),
        num(c.mean) if c.estimated else "-",
        interval,
        num(c.t_p),
        num(c.wilcoxon_p),
        num(c.effect),
        num(c.seeds_needed),
        c.verdict(higher_is_better(metric)),
    ]


def seeds_text(seeds: float) -> str:
    """Seeds for 80 % power as text.

    >>> seeds_text(23.0), seeds_text(math.inf), seeds_text(math.nan)
    ('23', '> 10000', '-')
    """
    return f"> {MOST_SEEDS}" if math.isinf(seeds) else num(seeds)


def contrast_table(section: Section) -> tuple[list[str], Table]:
    """The robustness contrasts of the section's metric (head, rows)."""
    return CONTRAST_HEAD, [contrast_row(c, section.metric) for c in section.contrasts]


def contrast_text(section: Section, axis: str) -> str:
    """What the contrast table means, in one paragraph."""
    direction = "higher" if higher_is_better(section.metric) else "lower"
    sizes = sorted({num(c.detect) for c in section.contrasts if c.estimated})
    detect = f" (a contrast of {', '.join(sizes)})" if sizes else ""
    return (
        f"Robustness contrast of {section.metric} over {axis}: per seed, (A at level - A at"
        f" baseline) - (B at level - B at baseline), the paired difference of the two"
        f" degradations; mean with its 95 % t interval, paired t-test and Wilcoxon p, effect"
        f" size d_z = mean / SD, and the seeds a paired t-test needs to detect the contrast"
        f"{detect} at 80 % power, alpha 0.05. {section.metric}: {direction} is better, so A is"
        f" more robust than B when the interval lies "
        f"{'above' if direction == 'higher' else 'below'} 0."
    )


def headline_lines(section: Section, axis: str) -> list[str]:
    """The robustness contrasts as lines for the terminal."""
    better_high = higher_is_better(section.metric)
    lines = [f"Is A more robust than B? Contrast of {section.metric} against {axis}:"]
    for c in section.contrasts:
        figures = (
            f"{num(c.mean)} [{num(c.ci_low)}, {num(c.ci_high)}], p {num(c.t_p)},"
            f" d_z {num(c.effect)}, {seeds_text(c.seeds_needed)} seeds for 80 % power"
            if c.estimated
            else f"{c.censored} of {c.seeds} seeds censored"
        )
        lines.append(
            f"  A {c.a}, B {c.b}, {axis} {c.level} vs {c.baseline}: {figures}:"
            f" {c.verdict(better_high)}"
        )
    return lines
