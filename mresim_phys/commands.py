"""The ``mresim`` commands' work (output edge): run, import-team, replay, plot, bench, and
``validate --explorable``.

``cli.py`` parses the command line and imports this module only when one of these commands
runs: it brings the simulator (numba, pymunk, OpenCV). ``mresim validate`` without
``--explorable`` never comes here (``validation.py``).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path

import yaml

from mresim_phys.errors import MresimError
from mresim_phys.metrics import StepRecord
from mresim_phys.output.bench import run_bench
from mresim_phys.output.explorable_report import print_team_report
from mresim_phys.output.files import write_text_atomic
from mresim_phys.output.health import print_warnings
from mresim_phys.output.plots import plot_runs
from mresim_phys.output.progress import first_run_note, progress_bar
from mresim_phys.output.recorders import default_run_dir
from mresim_phys.output.replay import replay_run
from mresim_phys.output.session import INTERRUPTED, Outcome, run_session
from mresim_phys.output.signals import StopRequest, stop_on_signals
from mresim_phys.run_args import (
    check_video_folder,
    draw_plots,
    render_overrides,
    simulation_overrides,
    summary_line,
)
from mresim_phys.scenario.load import resolve_map_path, validate_scenario
from mresim_phys.scenario.team_file import read_team_file
from mresim_phys.sim import Simulation
from mresim_phys.viewer import command as viewer
from mresim_phys.viewer.flags import check_run_flags


def bench_command(args: argparse.Namespace) -> int:
    """``mresim bench``: time full steps and print the cost split."""
    report = run_bench(
        args.robots, args.map, args.warmup, args.steps, args.preset, args.threads, args.strategies
    )
    print(report)
    return 0


def run_command(args: argparse.Namespace) -> int:
    """``mresim run``: simulate, streaming metrics (and log, video, PNGs) to the run folder.

    SIGINT and SIGTERM are handled from the start (building the simulation included): the
    run stops after the current step and still writes everything (``output.session``).
    """
    check_run_flags(args)
    if args.view:
        return viewer.view_run(args)
    linger = getattr(args, "program", False)  # see main()
    note = None if args.quiet else first_run_note()
    if note is not None:
        print(note, file=sys.stderr, flush=True)
    with stop_on_signals(StopRequest(notice=not args.quiet), linger=linger) as stop:
        sim = Simulation.from_yaml(
            args.scenario,
            seed=args.seed,
            steps=args.steps,
            render=render_overrides(args),
            **simulation_overrides(args),
        )
        check_video_folder(sim.scenario, args.scenario)
        out_dir = args.out or default_run_dir(sim.scenario)
        plotted: list[bool] = []

        def plots(folder: Path) -> None:
            wanted = sim.scenario.render.plots
            plotted.append(draw_plots(wanted, [folder], folder / "plots", args.quiet))

        outcome = run_with_bar(sim, out_dir, args, stop, plots)
    if not args.quiet:
        print(summary_line(sim, outcome, any(plotted)))
    print_warnings(outcome.summary)
    return outcome.exit_status


def run_with_bar(
    sim: Simulation,
    out_dir: Path,
    args: argparse.Namespace,
    stop: StopRequest,
    finish: Callable[[Path], object],
) -> Outcome:
    """run_session under a tqdm progress bar whose total is the steps run when a stop rule
    ends the run early."""
    scenario = sim.scenario
    bar = progress_bar(total=scenario.steps, disable=args.quiet, unit="step", desc=scenario.name)
    with bar:

        def progress(record: StepRecord) -> None:
            bar.update(0 if record.step == 0 else 1)
            bar.set_postfix(
                explored=f"{record.explored:.3f}", base=f"{record.known_at_base:.3f}", refresh=False
            )

        outcome = run_session(
            sim, out_dir, progress, overwrite=args.overwrite, stop=stop, finish=finish
        )
        if outcome.reason != INTERRUPTED:
            bar.total = bar.n
            bar.refresh()
    return outcome


def explorable_command(args: argparse.Namespace) -> int:
    """``mresim validate --explorable``: the run's world built (every check of a run's
    start), then where the team can go and what it can see, with warnings on stderr."""
    print_team_report(Simulation.from_yaml(args.scenario), str(args.scenario))
    return 0


def import_team_command(args: argparse.Namespace) -> int:
    """``mresim import-team``: the original's team file as a scenario YAML, validated."""
    data = read_team_file(args.team_file, args.map, args.strategy, args.comm)
    text = yaml.safe_dump(data, sort_keys=False, default_flow_style=None)
    source = str(args.team_file)
    folder = (args.out.parent if args.out is not None else Path.cwd()).resolve()
    scenario = resolve_map_path(validate_scenario(data, source=source), folder, source)
    try:
        Simulation(scenario)  # the map is read and every start checked against it
    except MresimError as exc:
        raise MresimError(f"{source} on map {args.map}: {exc}") from None
    if args.out is None:
        print(text, end="")
    else:
        write_text_atomic(args.out, text)
        print(f"{args.out}: {len(data['robots'])} robots from {args.team_file}")
    return 0


def replay_command(args: argparse.Namespace) -> int:
    """``mresim replay``: frames (and metrics) from a run's log, without re-simulating."""
    result = replay_run(args.run_dir, render_overrides(args), args.metrics)
    for line in result.lines:
        print(line)
    return 0 if result.ok else 1


def plot_command(args: argparse.Namespace) -> int:
    """``mresim plot``: exploration, distance and link figures for the given runs."""
    out_dir = args.out or (args.run_dirs[0] / "plots" if len(args.run_dirs) == 1 else Path("plots"))
    for path in plot_runs(list(args.run_dirs), out_dir):
        print(path)
    return 0
