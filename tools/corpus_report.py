"""Corpus reports (a script's module, phase: report): ``corpus.csv`` and ``corpus.md`` from
the rows ``tools/corpus.py`` makes, one per run, and whether each keeps the invariant.

The CSV holds :data:`COLUMNS` in order; the Markdown report gives, per map, the medians
over seeds of each strategy and team size (a milestone never reached is left out of its
median and counted), then every run that failed or broke the invariant.
"""

from __future__ import annotations

import csv
from collections import Counter
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

MILESTONES = ("0.5", "0.9", "0.95")
GOAL = 0.95  # the invariant: every run explores this share of the explorable area ...
IDLE_BOUND = 20  # ... and no robot idles longer with reachable frontier cells in its map

COLUMNS = (
    "map", "kind", "strategy", "size", "seed", "radii", "error", "steps", "stop_reason",
    "final_explored", "final_known_at_base",
    *(f"{what}_{level}_at" for level in MILESTONES for what in ("explored", "base")),
    "robots_active", "robots_done", "robots_error", "robots_failed", "robot_states", "alive",
    "robots_idle_with_frontier", "idle_robot_steps", "stuck_robot_steps", "robots_fruitless",
    "fruitless_robot_steps",
    "final_explored_connected", "robot_idle_with_frontier", "idlest_robot", "invariant",
    "cpu_s",
)  # fmt: skip


def violations(row: dict[str, Any]) -> list[str]:
    """How a run breaks the corpus invariant (none: it holds): it explored at least
    :data:`GOAL` of the explorable area, and no robot idled more than :data:`IDLE_BOUND`
    steps while its own map held frontier cells it could reach (waiting at a meeting point
    is not idling: ``knowledge/health.py``)."""
    if row["error"]:
        return [f"failed: {row['error']}"]
    found = []
    if float(row["final_explored"]) < GOAL:
        found.append(f"explored {row['final_explored']} after {row['steps']} steps")
    if int(row["robot_idle_with_frontier"]) > IDLE_BOUND:
        who, steps = row["idlest_robot"], row["robot_idle_with_frontier"]
        found.append(f"{who} idled {steps} steps with reachable frontier cells")
    return found


def write_csv(rows: Sequence[dict[str, Any]], path: Path) -> None:
    """One line per run, :data:`COLUMNS` in order."""
    with path.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.DictWriter(handle, fieldnames=COLUMNS, extrasaction="ignore")
        writer.writeheader()
        writer.writerows(rows)


def median(values: Sequence[Any]) -> str:
    """The median of the values that are set (milestones never reached are not), with how
    many were set when some are missing; '-' when none is."""
    given = [float(v) for v in values if v not in (None, "")]
    if not given:
        return "-"
    text = f"{float(np.median(given)):.3g}"
    return text if len(given) == len(values) else f"{text} ({len(given)}/{len(values)})"


def tally(values: Iterable[Any]) -> str:
    """'value x count' for each distinct value, most common first."""
    return ", ".join(f"{v} x{n}" for v, n in Counter(values).most_common())


TABLE_HEAD = (
    "| strategy | size | runs | explored | known at base | explored 50% at | 90% at"
    " | base 90% at | steps | stop | robots at the end | fruitless robot-steps |\n"
    "|---|---|---|---|---|---|---|---|---|---|---|---|"
)


def group_cells(strategy: str, size: int, group: Sequence[dict[str, Any]]) -> list[str]:
    """One table row: medians over the group's runs that did not fail."""
    ok = [r for r in group if not r["error"]]
    runs = f"{len(ok)}" + (f" ({len(group) - len(ok)} failed)" if len(ok) < len(group) else "")
    states: Counter[str] = Counter()
    for r in ok:
        for state in ("active", "done", "error", "failed"):
            states[state] += int(r[f"robots_{state}"])
    columns = ("final_explored", "final_known_at_base", "explored_0.5_at", "explored_0.9_at")
    return [
        strategy,
        str(size),
        runs,
        *(median([r[c] for r in ok]) for c in (*columns, "base_0.9_at", "steps")),
        tally(r["stop_reason"] for r in ok),
        ", ".join(f"{s} {n}" for s, n in states.items() if n),
        median([r.get("fruitless_robot_steps") for r in ok]),
    ]


def map_table(rows: Sequence[dict[str, Any]]) -> str:
    """The Markdown table of one map's rows: medians over seeds per strategy and size."""
    groups: dict[tuple[str, int], list[dict[str, Any]]] = {}
    for row in rows:
        groups.setdefault((row["strategy"], int(row["size"])), []).append(row)
    lines = [TABLE_HEAD]
    for (strategy, size), group in groups.items():
        lines.append("| " + " | ".join(group_cells(strategy, size, group)) + " |")
    return "\n".join(lines)


def report(rows: Sequence[dict[str, Any]]) -> str:
    """The Markdown report: one table per map, then every run that failed or broke the
    invariant (:func:`violations`)."""
    parts = ["# Corpus runs\n", "Medians over seeds; a milestone never reached is left out of"
             " its median, '(k/n)' says how many runs reached it.\n"]  # fmt: skip
    for name in dict.fromkeys(r["map"] for r in rows):
        mine = [r for r in rows if r["map"] == name]
        parts.append(f"## {name} ({mine[0]['kind']})\n\n{map_table(mine)}\n")
    broken = [r for r in rows if r.get("invariant")]
    parts.append(f"## Runs that break the invariant ({len(broken)} of {len(rows)})\n")
    parts += [
        f"- {r['map']} {r['strategy']} n{r['size']} seed {r['seed']}: {r['invariant']}"
        for r in broken
    ]
    return "\n".join(parts) + "\n"
