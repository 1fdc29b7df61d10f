"""Command-line helpers shared by mresim's commands (output edge): argparse number types, and
what ``mresim run`` makes of its command line (overrides, plots, the summary line).

Used by ``cli.py``, the viewer's live run (``viewer/command.py``, the same session with a
page attached) and the sweep commands (``sweeps/cli.py``), which ``cli.py`` imports.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any, TypeVar

from mresim_phys.errors import MresimError, ScenarioError
from mresim_phys.output.plots import plot_runs, plotting_available
from mresim_phys.output.session import Outcome
from mresim_phys.output.video import chosen_video_path
from mresim_phys.scenario.schema import Scenario
from mresim_phys.sim import Simulation

T = TypeVar("T")


def render_overrides(args: argparse.Namespace) -> dict[str, Any]:
    """The render-block fields given on the command line."""
    given = {
        "video": args.video,
        "fps": args.fps,
        "every": args.every,
        "layers": args.layers,
        "scale": args.scale,
        "snapshots": args.snapshot,
        "codec": getattr(args, "codec", None),
    }
    if getattr(args, "no_log", False):
        given["log"] = False
    if getattr(args, "no_plots", False):
        given["plots"] = False
    return {k: v for k, v in given.items() if v is not None}


def check_video_folder(scenario: Scenario, source: Path) -> None:
    """Refuse, before the run starts and naming the scenario file, a video path whose folder
    does not exist (the rule of :func:`~mresim_phys.output.video.chosen_video_path`)."""
    if isinstance(scenario.render.video, str):
        try:
            chosen_video_path(scenario.render.video)
        except MresimError as exc:
            raise ScenarioError(f"{source}: {exc}") from None


def simulation_overrides(args: argparse.Namespace) -> dict[str, Any]:
    """The simulation-block fields given on the command line (as an override)."""
    given: dict[str, Any] = {}
    if args.fixed:
        given["vary_with_seed"] = False
    if args.threads is not None:
        given["threads"] = args.threads
    if args.paired:
        given["paired"] = True
    return {"simulation": given} if given else {}


def duration(summary: dict[str, Any]) -> str:
    """`` (16.8 s)`` when the run is given in seconds too (``physical``), else ``""``."""
    physical = summary.get("physical")
    return f" ({physical['duration_s']:g} s)" if isinstance(physical, dict) else ""


def summary_line(sim: Simulation, outcome: Outcome, plotted: bool) -> str:
    """The one line ``mresim run`` prints at the end."""
    scenario, summary, out_dir = sim.scenario, outcome.summary, outcome.out_dir
    reason = outcome.reason + (f" by {outcome.signal}" if outcome.signal else "")
    paired = scenario.simulation.paired
    return (
        f"{scenario.name} seed {scenario.seed}: {summary['steps']} steps{duration(summary)}"
        f" ({reason}),"
        f" explored {summary['final_explored']:.3f}, at base"
        f" {summary['final_known_at_base']:.3f}, {summary['wall_time_s']:.1f} s -> {out_dir}"
        + (f"; video {outcome.video}" if outcome.video else "")
        + (f"; plots in {out_dir / 'plots'}" if plotted else "")
        + (f"; baseline in {out_dir / 'robustness.json'}" if paired and not outcome.signal else "")
    )


def draw_plots(wanted: bool, run_dirs: list[Path], out_dir: Path, quiet: bool) -> bool:
    """Plots at the end of a run when asked for and matplotlib is installed."""
    if not wanted:
        return False
    if not plotting_available():
        if not quiet:
            print("(plots skipped: pip install -e '.[plot]' for matplotlib and pandas)")
        return False
    plot_runs(run_dirs, out_dir)
    return True
