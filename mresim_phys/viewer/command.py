"""Viewer (output edge), command line: ``mresim view RUN_DIR`` and ``mresim run --view``.

``view`` indexes a run's log (``replaysource``) and serves it; ``run --view`` runs the
scenario as ``mresim run`` does (same outputs, same bytes) with the page attached
(``livesource``): the run waits for a page, and once it ends the viewer replays the run
folder it wrote until Ctrl-C. Both print the page's URL and open a browser only with
``--open``. Bad input (no run log, a damaged one, a port in use, a malformed
``--allow-host``) is a MresimError: one paragraph, exit 2.
"""

from __future__ import annotations

import argparse
import time
import webbrowser
from pathlib import Path

from mresim_phys.build import region_probe
from mresim_phys.errors import MresimError
from mresim_phys.output.health import print_warnings
from mresim_phys.output.recorders import default_run_dir
from mresim_phys.output.session import Outcome, run_session
from mresim_phys.output.signals import StopRequest, stop_on_signals
from mresim_phys.run_args import draw_plots, render_overrides, simulation_overrides, summary_line
from mresim_phys.sim import Simulation
from mresim_phys.viewer.flags import DEFAULT_HOST, DEFAULT_PORT
from mresim_phys.viewer.frames import FrameMaker
from mresim_phys.viewer.guard import is_local
from mresim_phys.viewer.livesource import LiveSource, ViewerStop
from mresim_phys.viewer.replaysource import ReplaySource
from mresim_phys.viewer.server import ViewerServer


def server_for(source: LiveSource | ReplaySource, args: argparse.Namespace) -> ViewerServer:
    """The server the flags ask for, not yet started."""
    host = args.host or DEFAULT_HOST
    port = DEFAULT_PORT if args.port is None else args.port
    if not 0 <= port <= 65535:
        raise MresimError(f"--port {port}: a port is 0 (any free port) to 65535")
    if not args.allow_remote and not is_local(host) and host != "localhost":
        print(f"viewer: serving on {host}, but only this machine may connect (--allow-remote)")
    try:
        return ViewerServer(source, host, port, args.allow_remote, args.allow_host or ())
    except ValueError as exc:  # a malformed --allow-host
        raise MresimError(str(exc)) from None


def announce(server: ViewerServer, what: str, args: argparse.Namespace) -> None:
    """Print the URL (always: it is how the page is found) and open it if asked."""
    print(f"viewer: {what} at {server.url} (Ctrl-C to quit)", flush=True)
    if args.open:
        webbrowser.open(server.url)


def serve_until_stopped(server: ViewerServer, stop: StopRequest | None = None) -> None:
    """Serve until SIGINT or SIGTERM (recorded in ``stop`` if given), then close the server."""
    if stop is None:
        with stop_on_signals(StopRequest(notice=False)) as own:
            return serve_until_stopped(server, own)
    try:
        while not stop.requested:
            time.sleep(0.1)
    finally:
        server.close()


def view_command(args: argparse.Namespace) -> int:
    """``mresim view RUN_DIR``: serve the run's log."""
    started = time.perf_counter()
    print(f"viewer: reading the run log of {args.run_dir} ...", flush=True)
    source = ReplaySource.open(args.run_dir)
    source.warm_up()
    server = server_for(source, args)
    server.start()
    took = time.perf_counter() - started
    announce(server, f"{args.run_dir} ({source.steps} steps, indexed in {took:.1f} s)", args)
    serve_until_stopped(server)
    return 0


def view_run(args: argparse.Namespace) -> int:
    """``mresim run SCENARIO --view``: the run, driven from the page; then its replay."""
    stop = ViewerStop(notice=not args.quiet)
    # Signals after the run (while its log is indexed, then while it is served) go to
    # ``later``; during the run, to ``stop``.
    with stop_on_signals(StopRequest(notice=False)) as later:
        with stop_on_signals(stop):
            sim = Simulation.from_yaml(
                args.scenario,
                seed=args.seed,
                steps=args.steps,
                render=render_overrides(args),
                **simulation_overrides(args),
            )
            server, live = live_server(sim, stop, args)
            try:
                outcome, plotted = live_session(sim, args, live, stop)
            except BaseException:
                server.close()
                raise
        if not args.quiet:
            print(summary_line(sim, outcome, plotted), flush=True)
        print_warnings(outcome.summary)
        replay_after(server, outcome, stop, later)
    return outcome.exit_status


def live_server(
    sim: Simulation, stop: ViewerStop, args: argparse.Namespace
) -> tuple[ViewerServer, LiveSource]:
    """The started server of a live run, its URL printed."""
    probe = region_probe(sim.scenario, sim.world)
    frames = FrameMaker(sim.world.shape, sim.scenario.render.scale, lambda _: probe)
    live = LiveSource(sim, stop, frames)
    server = server_for(live, args)
    server.start()
    announce(server, f"{sim.scenario.name} (the run starts when a page connects)", args)
    return server, live


def replay_after(
    server: ViewerServer, outcome: Outcome, stop: ViewerStop, later: StopRequest
) -> None:
    """Serve the finished run's log until a signal; at once close if a signal stopped the
    run or it has no log."""
    if stop.signum is not None or not (outcome.out_dir / "log").is_dir():
        server.close()
        return
    try:
        server.swap(ReplaySource.open(outcome.out_dir))
    except BaseException:
        server.close()
        raise
    print(f"viewer: the run ended; replaying {outcome.out_dir} at {server.url}", flush=True)
    serve_until_stopped(server, later)


def live_session(
    sim: Simulation, args: argparse.Namespace, live: LiveSource, stop: ViewerStop
) -> tuple[Outcome, bool]:
    """Run the session with the page's hook; whether plots were drawn."""
    out_dir = args.out or default_run_dir(sim.scenario)
    plotted: list[bool] = []

    def plots(folder: Path) -> None:
        wanted = sim.scenario.render.plots
        plotted.append(draw_plots(wanted, [folder], folder / "plots", args.quiet))

    outcome = run_session(
        sim, out_dir, live.on_step, overwrite=args.overwrite, stop=stop, finish=plots
    )
    live.end()
    return outcome, any(plotted)
