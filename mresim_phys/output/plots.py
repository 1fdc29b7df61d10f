"""Plots (output edge): exploration curves, distances and links of one or more runs.

Reads each run folder (``output.rundata``: ``metrics.csv``, ``summary.json`` and the
failures and blackouts of its log, all checked) and draws with matplotlib's
non-interactive Agg backend: ``exploration.png`` (explored and known-at-base vs
step, with the 50, 90 and 95 % levels), ``distance.png`` (per-robot distance vs step) and
``links.png`` (linked pairs and alive robots vs step); failures (dotted) and blackouts
(dash-dotted, from start to end, shaded between) are vertical lines on the exploration
and links figures. Several runs share each figure, one colour per run; each PNG is
written whole or not at all (``output.files``: WriteError when it cannot be). matplotlib and
pandas are the optional ``plot`` extra (``pip install -e ".[plot]"``); without them
plotting is skipped with a message.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mresim_phys.errors import MresimError
from mresim_phys.output.files import atomic_path, make_parent
from mresim_phys.output.rundata import RunEvent, read_metrics, run_events, run_label

FIGURE_SIZE = (8.0, 4.5)
DPI = 120
Units = tuple[float | None, float | None]  # (seconds per step, metres per cell)
LEVELS = (0.5, 0.9, 0.95)  # the milestones of summary.json


@dataclass(frozen=True)
class PlottedRun:
    """One run's label, metrics (a DataFrame) and failures and blackouts."""

    label: str
    df: Any
    events: Sequence[RunEvent] = ()


def plotting_available() -> bool:
    """Whether matplotlib and pandas can be imported."""
    try:
        import matplotlib  # noqa: F401
        import pandas  # noqa: F401
    except ImportError:
        return False
    return True


def plot_runs(run_dirs: list[Path], out_dir: Path) -> list[Path]:
    """Draw the three figures for ``run_dirs`` into ``out_dir``; return the PNG paths."""
    if not plotting_available():
        raise MresimError("plotting needs matplotlib and pandas: pip install -e '.[plot]'")
    import matplotlib

    matplotlib.use("Agg")
    runs = []
    for run_dir in run_dirs:
        df = read_metrics(run_dir)
        runs.append(PlottedRun(run_label(run_dir), df, run_events(run_dir, df)))
    units = shared_units(run_dirs)
    make_parent(out_dir / "exploration.png")
    return [
        draw_exploration(runs, out_dir / "exploration.png", units),
        draw_distance(runs, out_dir / "distance.png", units),
        draw_links(runs, out_dir / "links.png", units),
    ]


def run_units(run_dir: Path) -> tuple[float | None, float | None]:
    """(seconds per step, metres per cell) of a run given in seconds (summary.json's
    ``physical`` block, ``output/physical.py``); None where it has none or it is damaged."""
    try:
        summary = json.loads((run_dir / "summary.json").read_text(encoding="utf-8"))
        block = summary.get("physical", {}) if isinstance(summary, dict) else {}
    except (OSError, ValueError):
        return None, None
    found = [block.get(k) if isinstance(block, dict) else None for k in ("dt_s", "resolution_m")]
    dt, resolution = (v if positive(v) else None for v in found)
    return dt, resolution


def positive(value: Any) -> bool:
    """A finite number > 0 (not a bool)."""
    number = isinstance(value, int | float) and not isinstance(value, bool)
    return number and math.isfinite(value) and value > 0


def shared_units(run_dirs: list[Path]) -> tuple[float | None, float | None]:
    """The runs' common (dt, resolution); None for one they do not all share."""
    found = {run_units(d) for d in run_dirs}
    dts, resolutions = {f[0] for f in found}, {f[1] for f in found}
    return (
        next(iter(dts)) if len(dts) == 1 else None,
        next(iter(resolutions)) if len(resolutions) == 1 else None,
    )


def seconds_axis(ax: Any, dt: float | None) -> None:
    """A second x axis on top in seconds, for runs given in seconds."""
    if dt is not None:
        top = ax.secondary_xaxis("top", functions=(lambda s: s * dt, lambda t: t / dt))
        top.set_xlabel(f"seconds (dt {dt:g} s)")


def new_axes(title: str, ylabel: str) -> tuple[Any, Any]:
    """A figure with one labelled axes."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=FIGURE_SIZE, dpi=DPI)
    ax.set_title(title)
    ax.set_xlabel("step")
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)
    return fig, ax


def save(fig: Any, ax: Any, path: Path) -> Path:
    """Add the legend, write the PNG, free the figure."""
    import matplotlib.pyplot as plt

    try:
        ax.legend(loc="best", fontsize="small")
        fig.tight_layout()
        with atomic_path(path) as tmp:
            fig.savefig(tmp)
    finally:
        plt.close(fig)
    return path


def draw_events(ax: Any, run: PlottedRun, colour: str) -> None:
    """Failures (dotted) and blackouts (dash-dotted start and end, shaded) as vertical lines."""
    labelled: set[str] = set()
    for event in run.events:
        style = ":" if event.kind == "failure" else "-."
        label = None if event.kind in labelled else f"{run.label}: {event.kind}"
        labelled.add(event.kind)
        ax.axvline(event.step, color=colour, linestyle=style, linewidth=1, label=label)
        if event.kind == "blackout" and event.until is not None:
            ax.axvline(event.until, color=colour, linestyle=style, linewidth=1)
            ax.axvspan(event.step, event.until, color=colour, alpha=0.08)


def draw_levels(ax: Any) -> None:
    """Horizontal lines at the 50, 90 and 95 % milestones, labelled at the right edge."""
    for level in LEVELS:
        ax.axhline(level, color="grey", linestyle="--", linewidth=0.7, alpha=0.6)
        ax.annotate(
            f"{level:.0%}",
            (1.0, level),
            xycoords=("axes fraction", "data"),
            xytext=(2, 0),
            textcoords="offset points",
            va="center",
            fontsize="x-small",
            color="grey",
        )


def draw_exploration(runs: list[PlottedRun], path: Path, units: Units = (None, None)) -> Path:
    """Explored (solid) and known at base (dashed) fractions vs step, one colour per run,
    with the milestone levels and each run's failures and blackouts."""
    fig, ax = new_axes("Exploration", "fraction of reachable free space")
    seconds_axis(ax, units[0])
    for i, run in enumerate(runs):
        colour, df = f"C{i % 10}", run.df
        ax.plot(df["step"], df["explored"], color=colour, label=f"{run.label}: explored")
        ax.plot(
            df["step"],
            df["known_at_base"],
            color=colour,
            linestyle="--",
            label=f"{run.label}: known at base",
        )
        draw_events(ax, run, colour)
    draw_levels(ax)
    ax.set_ylim(0, 1.02)
    return save(fig, ax, path)


def draw_distance(runs: list[PlottedRun], path: Path, units: Units = (None, None)) -> Path:
    """Distance travelled by every robot vs step (and metres, given a resolution)."""
    fig, ax = new_axes("Distance travelled", "cells")
    seconds_axis(ax, units[0])
    res = units[1]
    if res is not None:
        right = ax.secondary_yaxis("right", functions=(lambda c: c * res, lambda m: m / res))
        right.set_ylabel(f"metres ({res:g} m per cell)")
    styles = ["-", "--", ":", "-."]
    for i, run in enumerate(runs):
        label, df = run.label, run.df
        robots = [c.removeprefix("distance_") for c in df.columns if c.startswith("distance_")]
        for j, robot in enumerate(robots):
            ax.plot(
                df["step"],
                df[f"distance_{robot}"],
                color=f"C{j % 10}",
                linestyle=styles[i % len(styles)],
                label=f"{label}: {robot}",
            )
    return save(fig, ax, path)


def draw_links(runs: list[PlottedRun], path: Path, units: Units = (None, None)) -> Path:
    """Linked pairs (solid) and alive robots (dotted) vs step, and failures and blackouts."""
    fig, ax = new_axes("Communication links", "count")
    seconds_axis(ax, units[0])
    for i, run in enumerate(runs):
        colour, label, df = f"C{i % 10}", run.label, run.df
        draw_events(ax, run, colour)
        ax.step(df["step"], df["links"], where="post", color=colour, label=f"{label}: links")
        ax.step(
            df["step"],
            df["alive"],
            where="post",
            color=colour,
            linestyle=":",
            label=f"{label}: alive robots",
        )
    return save(fig, ax, path)
