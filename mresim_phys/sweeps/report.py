"""Sweep report (sweeps, compare): ``report.md`` and ``report.html`` (figures embedded).

One table per metric: each arm's done runs, mean, median, 95 % CI, thresholds not reached
and failed runs (an arm whose runs all failed is there too);
then the paired differences against the reference arm (pairs, mean and median
difference, Wilcoxon W and p, rank-biserial effect size); then every failed or lost run
(lost: its worker, disk or connection failed; ``mresim sweep`` runs it again) with its
error and log. The opening paragraph counts done, failed and lost runs and the runs run
again after a lost or failed attempt. Numbers are shown with four significant digits.
"""

from __future__ import annotations

import base64
import html
import math
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from mresim_phys.output.files import write_text_atomic
from mresim_phys.sweeps.stats import ArmFigures, Grouping, Paired
from mresim_phys.sweeps.worker import DONE, FAILED, LOST

ARM_HEAD = ["arm", "runs", "mean", "median", "95 % CI", "not reached", "failed"]
PAIR_HEAD = ["arm", "pairs", "mean diff", "median diff", "Wilcoxon W", "p", "effect size r"]
Table = list[list[str]]


@dataclass(frozen=True)
class Section:
    """One metric's figures."""

    metric: str
    arms: list[ArmFigures]
    pairs: list[Paired]


def num(value: float) -> str:
    """A number with four significant digits ('-' for NaN).

    >>> num(1234.567), num(0.012345), num(float("nan"))
    ('1235', '0.01235', '-')
    """
    return "-" if math.isnan(value) else f"{value:.4g}"


def arm_table(section: Section) -> Table:
    """Rows of the per-arm table."""
    return [
        [
            a.arm,
            str(a.n),
            num(a.mean),
            num(a.median),
            f"[{num(a.ci_low)}, {num(a.ci_high)}]",
            str(a.not_reached),
            str(a.failed),
        ]
        for a in section.arms
    ]


def pair_table(section: Section) -> Table:
    """Rows of the paired-differences table."""
    return [
        [
            p.arm,
            str(p.pairs),
            num(p.mean_diff),
            num(p.median_diff),
            num(p.statistic),
            num(p.p_value),
            num(p.effect),
        ]
        for p in section.pairs
    ]


def failed_table(runs: pd.DataFrame) -> Table:
    """Rows listing every run that is not done (failed or lost)."""
    failed = runs[runs["status"] != DONE]
    return [
        [
            shown(r.run_id),
            shown(r.label),
            shown(r.seed),
            shown(r.status),
            shown(r.error),
            shown(r.log),
        ]
        for r in failed.itertuples()
    ]


def shown(value: object) -> str:
    """A table cell's text ('-' for a missing value).

    >>> shown(None), shown(float("nan")), shown(3)
    ('-', '-', '3')
    """
    return "-" if value is None or value != value else str(value)


def counts(runs: pd.DataFrame) -> str:
    """``12 runs, 10 done, 1 failed, 1 lost`` (and the runs run again)."""
    status = runs["status"]
    text = (
        f"{len(runs)} runs, {int((status == DONE).sum())} done,"
        f" {int((status == FAILED).sum())} failed, {int((status == LOST).sum())} lost"
    )
    if "attempt" in runs.columns:
        again = int((pd.to_numeric(runs["attempt"], errors="coerce") > 1).sum())
        text += f" ({again} run again after a lost or failed attempt)" if again else ""
    return text


def markdown_table(head: list[str], rows: Table) -> list[str]:
    """A markdown table."""
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    return lines + [
        "| " + " | ".join(cell.replace("|", "/") for cell in row) + " |" for row in rows
    ]


def html_table(head: list[str], rows: Table) -> str:
    """An HTML table."""
    cells = "".join(f"<th>{html.escape(h)}</th>" for h in head)
    body = "".join(
        "<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in row) + "</tr>" for row in rows
    )
    return f"<table><thead><tr>{cells}</tr></thead><tbody>{body}</tbody></table>"


def blocks(
    runs: pd.DataFrame, grouping: Grouping, sections: list[Section], title: str
) -> list[tuple[str, str | tuple[list[str], Table]]]:
    """The report as (kind, content) blocks: heading, text or table."""
    failed = failed_table(runs)
    out: list[tuple[str, str | tuple[list[str], Table]]] = [
        ("h1", f"Sweep {title}"),
        (
            "p",
            f"{counts(runs)};"
            f" arms by {', '.join(grouping.by)};"
            f" reference arm {grouping.label(grouping.reference)};"
            f" pairs share {', '.join(grouping.pair_keys)} (common random numbers).",
        ),
    ]
    for section in sections:
        out += [("h2", section.metric), ("table", (ARM_HEAD, arm_table(section)))]
        if section.pairs:
            out += [("p", f"Paired differences (arm - reference) of {section.metric}:")]
            out += [("table", (PAIR_HEAD, pair_table(section)))]
    out += [("h2", "Failed and lost runs")]
    out += (
        [("table", (["run", "arm", "seed", "status", "error", "log"], failed))]
        if failed
        else [("p", "None.")]
    )
    return out


def write_reports(
    out: Path,
    runs: pd.DataFrame,
    grouping: Grouping,
    sections: list[Section],
    pictures: list[Path],
    title: str,
) -> list[Path]:
    """Write report.md and report.html into ``out``; their paths."""
    parts = blocks(runs, grouping, sections, title)
    md: list[str] = []
    page: list[str] = []
    for kind, content in parts:
        if isinstance(content, tuple):
            md += [*markdown_table(*content), ""]
            page.append(html_table(*content))
        else:
            md += [("# " if kind == "h1" else "## " if kind == "h2" else "") + content, ""]
            page.append(f"<{kind}>{html.escape(content)}</{kind}>")
    md += ["## Figures", ""] + [f"![{p.stem}]({p.name})" for p in pictures]
    page += ["<h2>Figures</h2>"] + [embedded(p) for p in pictures]
    style = "table{border-collapse:collapse}td,th{border:1px solid #999;padding:2px 6px}"
    document = f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}"
    document += f"</title><style>{style}</style></head><body>{''.join(page)}</body></html>\n"
    return [
        write_text_atomic(out / "report.md", "\n".join(md) + "\n"),
        write_text_atomic(out / "report.html", document),
    ]


def embedded(picture: Path) -> str:
    """An <img> holding ``picture`` as base64 data."""
    data = base64.b64encode(picture.read_bytes()).decode("ascii")
    return f"<p><img alt='{html.escape(picture.stem)}' src='data:image/png;base64,{data}'></p>"
