"""Plots (output edge): exploration curves, distances and links of one or more runs.

Reads each run folder's ``metrics.csv`` (pandas) and draws with matplotlib's
non-interactive Agg backend: ``exploration.png`` (explored and known-at-base vs
step), ``distance.png`` (per-robot distance vs step) and ``links.png`` (linked
pairs and alive robots vs step). Several runs share each figure, one colour per
run. matplotlib and pandas are the optional ``plot`` extra
(``pip install -e ".[plot]"``); without them plotting is skipped with a message.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from mresim_phys.errors import MresimError

FIGURE_SIZE = (8.0, 4.5)
DPI = 120


def plotting_available() -> bool:
    """Whether matplotlib and pandas can be imported."""
    try:
        import matplotlib  # noqa: F401
        import pandas  # noqa: F401
    except ImportError:
        return False
    return True


def run_label(run_dir: Path) -> str:
    """``name seed N`` from the run's summary, else the folder path."""
    summary = run_dir / "summary.json"
    if summary.exists():
        data = json.loads(summary.read_text(encoding="utf-8"))
        return f"{data.get('name', run_dir.name)} seed {data.get('seed', '?')}"
    return str(run_dir)


def read_metrics(run_dir: Path) -> Any:
    """The run's metrics as a DataFrame; MresimError if the folder holds none."""
    import pandas as pd

    path = run_dir / "metrics.csv"
    if not path.is_file():
        raise MresimError(
            f"{run_dir} is not a run folder: it has no metrics.csv. Give the folder that"
            " 'mresim run' wrote (e.g. runs/<name>/seed-<seed>)."
        )
    return pd.read_csv(path)


def plot_runs(run_dirs: list[Path], out_dir: Path) -> list[Path]:
    """Draw the three figures for ``run_dirs`` into ``out_dir``; return the PNG paths."""
    if not plotting_available():
        raise MresimError("plotting needs matplotlib and pandas: pip install -e '.[plot]'")
    import matplotlib

    matplotlib.use("Agg")
    runs = [(run_label(d), read_metrics(d)) for d in run_dirs]
    out_dir.mkdir(parents=True, exist_ok=True)
    return [
        draw_exploration(runs, out_dir / "exploration.png"),
        draw_distance(runs, out_dir / "distance.png"),
        draw_links(runs, out_dir / "links.png"),
    ]


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

    ax.legend(loc="best", fontsize="small")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return path


def draw_exploration(runs: list[tuple[str, Any]], path: Path) -> Path:
    """Explored (solid) and known at base (dashed) fractions vs step, one colour per run."""
    fig, ax = new_axes("Exploration", "fraction of reachable free space")
    for i, (label, df) in enumerate(runs):
        colour = f"C{i % 10}"
        ax.plot(df["step"], df["explored"], color=colour, label=f"{label}: explored")
        ax.plot(
            df["step"],
            df["known_at_base"],
            color=colour,
            linestyle="--",
            label=f"{label}: known at base",
        )
    ax.set_ylim(0, 1.02)
    return save(fig, ax, path)


def draw_distance(runs: list[tuple[str, Any]], path: Path) -> Path:
    """Distance travelled by every robot vs step."""
    fig, ax = new_axes("Distance travelled", "cells")
    styles = ["-", "--", ":", "-."]
    for i, (label, df) in enumerate(runs):
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


def draw_links(runs: list[tuple[str, Any]], path: Path) -> Path:
    """Linked pairs (solid) and alive robots (dotted) vs step."""
    fig, ax = new_axes("Communication links", "count")
    for i, (label, df) in enumerate(runs):
        colour = f"C{i % 10}"
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
