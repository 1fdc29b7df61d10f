"""Command line (output edge): ``mresim run | validate``.

Argument parsing only; the work is delegated to ``load``, ``sim`` and
``recorders``. Every user mistake ends in a one-paragraph message on stderr and
exit status 2, never a traceback; an interrupted run still writes its summary.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence
from pathlib import Path

from tqdm import tqdm

from .bench import run_bench
from .errors import MresimError
from .recorders import RunWriter, default_run_dir, summarise
from .sim import Simulation

EXIT_USER_ERROR = 2


def positive_int(text: str) -> int:
    """argparse type: an integer >= 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a number >= 1, got {value}")
    return value


def non_negative_int(text: str) -> int:
    """argparse type: an integer >= 0."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a number >= 0, got {value}")
    return value


def make_parser() -> argparse.ArgumentParser:
    """The ``mresim`` argument parser."""
    parser = argparse.ArgumentParser(
        prog="mresim", description="Multi-robot exploration simulator (mresim_phys)."
    )
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    run = commands.add_parser("run", help="run a scenario and write metrics")
    run.add_argument("scenario", type=Path, help="scenario YAML file")
    run.add_argument("--steps", type=positive_int, help="override the step cap")
    run.add_argument("--seed", type=non_negative_int, help="override the scenario seed")
    run.add_argument("--out", type=Path, help="output folder (default runs/<name>/seed-<seed>)")
    run.add_argument("--quiet", action="store_true", help="no progress bar or summary line")
    validate = commands.add_parser("validate", help="check a scenario without running it")
    validate.add_argument("scenario", type=Path, help="scenario YAML file")
    bench = commands.add_parser("bench", help="median ms per step for 4, 8, 16 robots")
    bench.add_argument("--robots", type=robot_counts, default=(4, 8, 16),
                       help="comma-separated team sizes (default 4,8,16)")
    bench.add_argument("--warmup", type=non_negative_int, default=50, help="untimed steps")
    bench.add_argument("--steps", type=positive_int, default=200, help="timed steps")
    bench.add_argument("--map", type=Path, help="an 800x600 floor plan (default maps/office.png)")
    return parser


def robot_counts(text: str) -> tuple[int, ...]:
    """argparse type: comma-separated positive team sizes."""
    return tuple(positive_int(part) for part in text.split(",") if part.strip())


def bench_command(args: argparse.Namespace) -> int:
    """``mresim bench``: time full steps and print the cost split."""
    print(run_bench(args.robots, args.map, args.warmup, args.steps))
    return 0


def run_command(args: argparse.Namespace) -> int:
    """``mresim run``: simulate, streaming metrics to the run folder."""
    sim = Simulation.from_yaml(args.scenario, seed=args.seed, steps=args.steps)
    scenario = sim.scenario
    out_dir = args.out or default_run_dir(scenario)
    started = time.perf_counter()
    reason = "interrupted"
    with (
        RunWriter(out_dir, scenario) as writer,
        tqdm(total=scenario.steps, disable=args.quiet, unit="step", desc=scenario.name) as bar,
    ):
        try:
            for record in sim.iterate():
                writer.on_step(record)
                bar.update(0 if record.step == 0 else 1)
                bar.set_postfix(
                    explored=f"{record.explored:.3f}",
                    base=f"{record.known_at_base:.3f}",
                    refresh=False,
                )
            reason = sim.stop_reason() or "steps"
        except KeyboardInterrupt:
            pass
        elapsed = time.perf_counter() - started
        summary = summarise(scenario, sim.record, sim.milestones, elapsed, reason)
        path = writer.write_summary(summary)
    if not args.quiet:
        print(
            f"{scenario.name} seed {scenario.seed}: {summary['steps']} steps ({reason}),"
            f" explored {summary['final_explored']:.3f}, at base"
            f" {summary['final_known_at_base']:.3f}, {elapsed:.1f} s -> {path.parent}"
        )
    return 130 if reason == "interrupted" else 0


def validate_command(args: argparse.Namespace) -> int:
    """``mresim validate``: schema, plugins, map and robot starts, without running."""
    scenario = Simulation.from_yaml(args.scenario).scenario
    print(f"{args.scenario}: ok ({len(scenario.robots)} robots, map {scenario.map.source[1]})")
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``mresim`` console script."""
    args = make_parser().parse_args(argv)
    handler = {"run": run_command, "validate": validate_command, "bench": bench_command}[
        args.command
    ]
    try:
        return handler(args)
    except MresimError as exc:
        print(f"mresim: error: {exc}", file=sys.stderr)
        return EXIT_USER_ERROR


if __name__ == "__main__":
    sys.exit(main())
