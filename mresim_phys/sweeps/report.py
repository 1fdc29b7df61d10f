"""Sweep report (sweeps, compare): ``report.md`` and ``report.html`` (figures embedded).

When the sweep has a fault axis, the report opens with its answer to "is A more robust
than B": the robustness contrast of the headline metric (``sweeps/contrast.py``). Then
one section per metric: for a metric every run has, each arm's runs, mean, median, 95 % CI
and failed runs, and the paired differences against the reference arm (pairs, mean and
median difference, Wilcoxon W and p, rank-biserial effect size); for a steps-to-threshold
metric, each arm's runs, reached and not reached (count and share), the Kaplan-Meier median
with its 95 % CI, and log-rank tests against the reference arm; then the metric's
contrasts. An arm whose runs all failed is there too. Then every failed or lost run
(lost: its worker, disk or connection failed; ``mresim sweep`` runs it again) with its
error and log. The opening paragraph counts done, failed and lost runs and the runs run
again after a lost or failed attempt. Numbers are shown with four significant digits.
"""

from __future__ import annotations

import base64
import html
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from mresim_phys.output.files import write_text_atomic
from mresim_phys.sweeps.report_tables import (
    Section,
    arm_table,
    contrast_table,
    contrast_text,
    pair_table,
)
from mresim_phys.sweeps.stats import Grouping
from mresim_phys.sweeps.survival import is_time_to_event
from mresim_phys.sweeps.worker import DONE, FAILED, LOST

Table = list[list[str]]


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


Block = tuple[str, str | tuple[list[str], Table]]
CENSORED = (
    "Times to a threshold are censored when a run never reached it (at its last step): per"
    " arm the share not reached, the Kaplan-Meier median and its 95 % interval; the log-rank"
    " test against the reference arm. No mean is taken over them."
)


def blocks(
    runs: pd.DataFrame,
    grouping: Grouping,
    sections: list[Section],
    title: str,
    headline: Headline | None = None,
) -> list[Block]:
    """The report as (kind, content) blocks: heading, text or table."""
    failed = failed_table(runs)
    out: list[Block] = [
        ("h1", f"Sweep {title}"),
        (
            "p",
            f"{counts(runs)};"
            f" arms by {', '.join(grouping.by)};"
            f" reference arm {grouping.label(grouping.reference)};"
            f" pairs share {', '.join(grouping.pair_keys)} (common random numbers).",
        ),
    ]
    if headline is not None:
        out += headline_blocks(headline)
    for section in sections:
        out += section_blocks(section, headline.axis if headline else None)
    out += [("h2", "Failed and lost runs")]
    out += (
        [("table", (["run", "arm", "seed", "status", "error", "log"], failed))]
        if failed
        else [("p", "None.")]
    )
    return out


@dataclass(frozen=True)
class Headline:
    """The report's opening answer: the robustness contrast of one metric over the fault
    axis."""

    section: Section
    axis: str


def headline_blocks(headline: Headline) -> list[Block]:
    """ "Is A more robust than B?": the contrast table of the headline metric, first."""
    section = headline.section
    return [
        ("h2", f"Is A more robust than B? ({section.metric} against {headline.axis})"),
        ("p", contrast_text(section, headline.axis)),
        ("table", contrast_table(section)),
    ]


def section_blocks(section: Section, axis: str | None) -> list[Block]:
    """One metric's heading, per-arm table, comparisons and contrasts."""
    out: list[Block] = [("h2", section.metric)]
    if is_time_to_event(section.metric):
        out.append(("p", CENSORED))
    out.append(("table", arm_table(section)))
    if section.pairs:
        kind = "Log-rank tests" if is_time_to_event(section.metric) else "Paired differences"
        out += [("p", f"{kind} (arm against the reference arm) of {section.metric}:")]
        out += [("table", pair_table(section))]
    if section.contrasts and axis is not None:
        out += [("p", contrast_text(section, axis)), ("table", contrast_table(section))]
    return out


def write_reports(
    out: Path,
    runs: pd.DataFrame,
    grouping: Grouping,
    sections: list[Section],
    pictures: list[Path],
    title: str,
    headline: Headline | None = None,
) -> list[Path]:
    """Write report.md and report.html into ``out``; their paths."""
    parts = blocks(runs, grouping, sections, title, headline)
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
