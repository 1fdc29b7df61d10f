"""Command line (output edge): ``mresim run | validate | replay | view | plot | bench |
warmup | make-map | make-set`` (and ``sweep | compare | robustness``, from ``sweeps/cli.py``).

Argument parsing and dispatch only, with light imports: each command's work
(``commands.py``, ``validation.py``, ``viewer/command.py``, ``sweeps/cli.py``) is imported
when that command runs, so ``mresim validate`` never loads numba, pymunk or OpenCV. Every
user mistake ends in a one-paragraph message on stderr and exit status 2, never a
traceback. A run stopped by SIGINT (Ctrl-C) or SIGTERM still closes its files and writes
its summary (``output.session``), then exits with 130 or 143.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Literal

from mresim_phys.arg_types import (
    add_settings,
    comma_separated,
    non_negative_int,
    positive_float,
    positive_int,
)
from mresim_phys.errors import MresimError
from mresim_phys.plugin import named_object
from mresim_phys.render.layers import GLOBAL_LAYERS, ROBOT_LAYERS
from mresim_phys.strategies.catalog import STRATEGIES
from mresim_phys.sweeps.cli import SWEEP_COMMANDS, add_sweep_parsers
from mresim_phys.viewer.flags import add_run_view_flags, add_view_parser

EXIT_USER_ERROR = 2
# output/bench.py's PRESETS (tested equal)
BENCH_PRESETS = ("office", "original", "rooms", "campus")
EXIT_INTERRUPTED = 130  # Ctrl-C outside a run's own handling (128 + SIGINT)
LAYERS_HELP = (
    "comma-separated layers applied in order: 'default', 'all', NAME to add, -NAME to remove,"
    " ROBOT:NAME+NAME-NAME for one robot (e.g. 'default,B:free_space'). Global layers: "
    + ", ".join(GLOBAL_LAYERS)
    + "; robot layers: "
    + ", ".join(ROBOT_LAYERS)
)


def package_version() -> str:
    """The installed version of mresim_phys (``unknown`` when run from a bare source tree)."""
    try:
        return version("mresim_phys")
    except PackageNotFoundError:
        return "unknown"


def make_parser() -> argparse.ArgumentParser:
    """The ``mresim`` argument parser."""
    parser = argparse.ArgumentParser(
        prog="mresim", description="Multi-robot exploration simulator (mresim_phys)."
    )
    parser.add_argument("--version", action="version", version=f"mresim {package_version()}")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    run = commands.add_parser("run", help="run a scenario and write metrics")
    run.add_argument("scenario", type=Path, help="scenario YAML file")
    run.add_argument("--steps", type=positive_int, help="override the step cap")
    run.add_argument("--seed", type=non_negative_int, help="override the scenario seed")
    run.add_argument("--out", type=Path, help="output folder (default runs/<name>/seed-<seed>)")
    run.add_argument(
        "--overwrite",
        action="store_true",
        help="replace the output folder even if it holds another scenario's run or other files",
    )
    run.add_argument(
        "--fixed",
        action="store_true",
        help="the seed varies nothing by itself (simulation.vary_with_seed: false)",
    )
    run.add_argument(
        "--threads",
        type=thread_setting,
        metavar="N",
        help="threads for the robots within a step (a number or auto; simulation.threads)",
    )
    run.add_argument("--quiet", action="store_true", help="no progress bar or summary line")
    add_render_flags(run)
    add_run_view_flags(run)
    run.add_argument("--no-log", action="store_true", help="do not write the run log")
    run.add_argument("--no-plots", action="store_true", help="do not draw plots at the end")
    run.add_argument(
        "--paired",
        action="store_true",
        help="also run the scenario without its faults as a baseline; write robustness.json",
    )
    team = commands.add_parser(
        "import-team", help="turn the original MRESim's team file into a scenario YAML"
    )
    team.add_argument("team_file", type=Path, help="the original's team file (11 columns)")
    team.add_argument(
        "--map",
        required=True,
        help="the map image the scenario uses (as written in the YAML: relative to --out's"
        " folder, or to the current folder without --out)",
    )
    team.add_argument("--strategy", default="frontier", help="the team's strategy (frontier)")
    team.add_argument(
        "--comm",
        default="path_loss",
        help="the communication model (path_loss: the original's PropModel1, its default)",
    )
    team.add_argument("--out", type=Path, help="where to write the YAML (default: stdout)")
    validate = commands.add_parser("validate", help="check a scenario without running it")
    validate.add_argument("scenario", type=Path, help="scenario YAML file")
    validate.add_argument(
        "--explorable",
        action="store_true",
        help="also build the run's world (each start's clearance from the exact walls, doors,"
        " terrain, prior map) and report where the team can go and what it can see",
    )
    replay = commands.add_parser("replay", help="re-render a run (and its metrics) from its log")
    replay.add_argument("run_dir", type=Path, help="a run folder written by 'mresim run'")
    add_render_flags(replay)
    replay.add_argument(
        "--metrics", action="store_true", help="recompute metrics.csv from the log and compare"
    )
    export = commands.add_parser(
        "export-map", help="write a robot's, the base's or the true map as a ROS map (YAML + PGM)"
    )
    export.add_argument("run_dir", type=Path, help="a run folder written by 'mresim run'")
    export.add_argument(
        "--map", default="base", help="a robot's name, 'base' or 'truth' (default: base)"
    )
    export.add_argument("--step", type=int, help="the logged step (default: the last)")
    export.add_argument("--out", type=Path, help="folder for the files (default: RUN_DIR/maps)")
    add_view_parser(commands)
    add_make_map_parser(commands)
    plot = commands.add_parser("plot", help="plot one or more runs' metrics")
    plot.add_argument("run_dirs", type=Path, nargs="+", help="run folders")
    plot.add_argument("--out", type=Path, help="folder for the PNGs (default: the run's plots/)")
    warmup = commands.add_parser(
        "warmup", help="compile the simulator's kernels once (after an install)"
    )
    warmup.add_argument(
        "--workers", type=positive_int, help="profiles compiled at once (default: the cores)"
    )
    warmup.add_argument(
        "--profiles", type=profile_names, help="comma-separated profiles (default: all)"
    )
    warmup.add_argument("--list", action="store_true", help="list the profiles and stop")
    bench = commands.add_parser("bench", help="median ms per step for 4, 8, 16 robots")
    bench.add_argument(
        "--robots",
        type=robot_counts,
        default=(4, 8, 16),
        help="comma-separated team sizes (default 4,8,16)",
    )
    bench.add_argument(
        "--preset",
        choices=BENCH_PRESETS,
        default="office",
        help="office: speed 3, laser 100, comm 150 on the office floor (default); original:"
        " the original MRESim's settings (speed 10, laser 200, comm 200, radius 0.5) on its"
        " library layout; rooms: the same on its rooms layout; campus: the same with disk"
        " comm on a generated 4000x4000 building (drawn once, then cached)",
    )
    bench.add_argument(
        "--warmup",
        type=non_negative_int,
        help="untimed steps (default: office 50, campus 5, others 10)",
    )
    bench.add_argument(
        "--steps",
        type=positive_int,
        help="timed steps (default: office 200, campus 20, others 100)",
    )
    bench.add_argument("--map", type=Path, help="another 800x600 floor plan for the preset")
    bench.add_argument(
        "--threads",
        type=thread_settings,
        default=(1,),
        metavar="N,N",
        help="thread counts to compare, e.g. 1,2 or 1,auto (default 1): one run per count,"
        " stepped in turn",
    )
    bench.add_argument(
        "--strategies",
        type=strategy_names,
        default=("frontier",),
        metavar="NAME,NAME",
        help="strategies to compare, e.g. frontier,hungarian,role_based:multi_point (default"
        " frontier): one run per strategy, stepped in turn; relay strategies pair the team",
    )
    add_sweep_parsers(commands)
    return parser


def add_render_flags(parser: argparse.ArgumentParser) -> None:
    """Flags that override the scenario's ``render`` block."""
    parser.add_argument(
        "--video",
        nargs="?",
        const=True,
        default=None,
        metavar="PATH",
        help="write a video (default videos/<name>-seed<seed>.mp4, H.264; .webm too)",
    )
    parser.add_argument(
        "--codec",
        choices=("h264", "mp4v", "vp8", "mjpg"),
        help="video codec (default from the extension: .mp4 H.264, .webm VP8)",
    )
    parser.add_argument("--fps", type=positive_float, help="video frames per second")
    parser.add_argument("--every", type=positive_int, help="one frame every N steps")
    parser.add_argument("--layers", metavar="L", help=LAYERS_HELP)
    parser.add_argument("--scale", type=positive_float, help="frame scale (2 = twice the map)")
    parser.add_argument(
        "--snapshot",
        type=step_list,
        metavar="STEPS",
        help="write PNG frames at these steps, e.g. 100,500",
    )


def step_list(text: str) -> list[int]:
    """argparse type: comma-separated step numbers."""
    return [non_negative_int(part) for part in text.split(",") if part.strip()]


def profile_names(text: str) -> list[str]:
    """argparse type of ``mresim warmup --profiles``: comma-separated names."""
    return comma_separated(text, str.strip, "profile names such as core,radio")


def robot_counts(text: str) -> tuple[int, ...]:
    """argparse type: comma-separated positive team sizes (at least one)."""
    return tuple(comma_separated(text, positive_int, "team sizes such as 4,8,16"))


def add_make_map_parser(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """The make-map sub-command (``mapgen/``)."""
    make = commands.add_parser(
        "make-map",
        help="draw a seeded building, office, cave or rubble site (docs/procedural-maps.md)",
    )
    make.add_argument("kind", choices=("building", "office", "cave", "rubble", "blueprint"))
    make.add_argument("--seed", type=non_negative_int, default=0, help="the map's seed (default 0)")
    make.add_argument(
        "--size", type=map_size, required=True, metavar="WxH", help="cells, e.g. 400x300"
    )
    make.add_argument(
        "--out", type=Path, required=True, help="folder for map.png, map.yaml, scenario.yaml"
    )
    make.add_argument("--robots", type=positive_int, default=4, help="starts to place (default 4)")
    make.add_argument(
        "--radius", type=positive_float, default=2.0, help="body radius the starts fit (default 2)"
    )
    add_settings(
        make, "a parameter of the kind, e.g. room_min=20 (repeatable; docs/procedural-maps.md)"
    )
    maps = commands.add_parser(
        "make-set", help="draw a set of procedural maps with a train/test split"
    )
    maps.add_argument("set_file", type=Path, help="set YAML file (docs/procedural-maps.md)")
    maps.add_argument("--out", type=Path, required=True, help="folder for the maps and set.yaml")


def map_size(text: str) -> tuple[int, int]:
    """argparse type: ``WxH`` in cells."""
    width, sep, height = text.lower().partition("x")
    if not sep:
        raise argparse.ArgumentTypeError(f"expected WxH such as 400x300, got {text!r}")
    return positive_int(width), positive_int(height)


def thread_setting(text: str) -> int | Literal["auto"]:
    """argparse type: ``auto`` or a thread count >= 1."""
    return "auto" if text.strip() == "auto" else positive_int(text)


def thread_settings(text: str) -> tuple[int | Literal["auto"], ...]:
    """argparse type: comma-separated thread settings (at least one)."""
    settings = tuple(thread_setting(part) for part in text.split(",") if part.strip())
    if not settings:
        raise argparse.ArgumentTypeError(f"expected thread counts such as 1,2, got {text!r}")
    return settings


def strategy_names(text: str) -> tuple[str, ...]:
    """argparse type: comma-separated registered strategy names (at least one), each
    optionally ``:rendezvous`` (``role_based:multi_point``)."""
    names = tuple(part.strip() for part in text.split(",") if part.strip())
    unknown = [n for n in names if n.partition(":")[0] not in STRATEGIES.names()]
    if not names or unknown:
        known = ", ".join(sorted(STRATEGIES.names()))
        raise argparse.ArgumentTypeError(f"expected strategy names ({known}), got {text!r}")
    return names


COMMANDS: dict[str, str | Callable[[argparse.Namespace], int]] = {
    # command -> "module:function" doing its work, imported when the command runs
    "run": "mresim_phys.commands:run_command",
    "validate": "mresim_phys.validation:validate_command",
    "import-team": "mresim_phys.commands:import_team_command",
    "replay": "mresim_phys.commands:replay_command",
    "export-map": "mresim_phys.output.rosmap:export_map_command",
    "plot": "mresim_phys.commands:plot_command",
    "bench": "mresim_phys.commands:bench_command",
    "warmup": "mresim_phys.output.warmup:warmup_command",
    "view": "mresim_phys.viewer.command:view_command",
    "make-map": "mresim_phys.mapgen.command:make_map_command",
    "make-set": "mresim_phys.mapgen.command:make_set_command",
    **SWEEP_COMMANDS,
}


def handler_of(command: str) -> Callable[[argparse.Namespace], int]:
    """The function doing ``command``'s work (its module imported now)."""
    handler = COMMANDS[command]
    found: Callable[[argparse.Namespace], int] = (
        named_object(handler) if isinstance(handler, str) else handler
    )
    return found


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``mresim`` console script.

    Without ``argv`` (the process's own command line: the console script, ``python -m``)
    mresim is about to exit when this returns, so after a run stopped by a signal, further
    stop signals stay ignored (``stop_on_signals(linger=True)``); called with ``argv`` (in
    process), the previous handlers always come back.
    """
    args = make_parser().parse_args(argv)
    args.program = argv is None
    try:
        return handler_of(args.command)(args)
    except KeyboardInterrupt:
        print("mresim: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except MresimError as exc:
        print(f"mresim: error: {exc}", file=sys.stderr)
        return EXIT_USER_ERROR
    except OSError as exc:
        print(
            f"mresim: error: cannot use {exc.filename or 'a file'}: {exc.strerror or exc}."
            " Check that the folder exists or can be created and that you may write there.",
            file=sys.stderr,
        )
        return EXIT_USER_ERROR


if __name__ == "__main__":
    sys.exit(main())
