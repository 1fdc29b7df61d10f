"""Command line of sweeps (output edge): ``mresim sweep | compare | robustness``.

Argument parsing only. The work is imported when a command runs, so other ``mresim``
commands never load pandas, pyarrow, matplotlib or Dask (the optional ``sweep`` extra);
without them these commands say what to install (exit 2).
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
from pathlib import Path

from mresim_phys.arg_types import comma_separated, positive_float, positive_int, whole_number
from mresim_phys.errors import MresimError
from mresim_phys.sweeps.study import Study  # no pandas, pyarrow or matplotlib behind it

NEEDED = ("pandas", "pyarrow", "matplotlib", "scipy", "statsmodels")


def require_extra(dask: bool = False) -> None:
    """MresimError naming what to install when an optional dependency is missing."""
    missing = [m for m in (*NEEDED, *(["distributed"] if dask else [])) if not installed(m)]
    if missing:
        raise MresimError(
            f"sweeps need {', '.join(missing)}, which are not installed;"
            " pip install -e '.[sweep]' (or pip install 'mresim_phys[sweep]')."
        )


def installed(module: str) -> bool:
    """Whether ``module`` can be imported."""
    return importlib.util.find_spec(module) is not None


def counts(text: str) -> list[int]:
    """argparse type: comma-separated whole numbers >= 0 (at least one)."""
    return comma_separated(text, lambda part: whole_number(part, 0), "numbers such as 0,1,2,3")


def names(text: str) -> list[str]:
    """argparse type: comma-separated names (at least one)."""
    return comma_separated(text, str.strip, "comma-separated names")


def window(text: str) -> tuple[float, float]:
    """argparse type: two fractions ``LOW,HIGH`` of the step cap."""
    try:
        low, high = (float(part) for part in text.split(","))
    except ValueError:
        message = f"expected LOW,HIGH such as 0.05,0.35, got {text!r}"
        raise argparse.ArgumentTypeError(message) from None
    return low, high


def shard_arg(text: str) -> tuple[int, int]:
    """``--shard i/N``."""
    from mresim_phys.sweeps.shards import parse_shard

    try:
        return parse_shard(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def add_backend_flags(parser: argparse.ArgumentParser) -> None:
    """--workers / --dask, --out, --verbose, --quiet."""
    where = parser.add_mutually_exclusive_group()
    where.add_argument(
        "--workers",
        type=positive_int,
        metavar="N",
        help="local worker processes (default: the cores)",
    )
    where.add_argument(
        "--dask",
        metavar="ADDRESS",
        help="run on Dask: local:N starts a LocalCluster of N workers;"
        " tcp://host:8786 joins a running scheduler",
    )
    parser.add_argument("--out", type=Path, help="sweep folder (default sweeps/<study name>)")
    parser.add_argument(
        "--retry-failed",
        action="store_true",
        help="run the runs that failed of their own error again (lost runs always run again)",
    )
    parser.add_argument("--verbose", action="store_true", help="print each run as it starts/ends")
    parser.add_argument("--quiet", action="store_true", help="no progress bar or summary")


def add_compare_flags(parser: argparse.ArgumentParser) -> None:
    """--metric, --reference, --svg."""
    parser.add_argument(
        "--metric",
        type=names,
        metavar="NAME,NAME",
        help="metrics of the report (default steps_to_explored_90,"
        " steps_to_known_at_base_90, auc_explored, auc_known_at_base,"
        " final_explored); the first is plotted",
    )
    parser.add_argument("--reference", help="the reference arm: its label or one of its values")
    parser.add_argument(
        "--detect",
        type=positive_float,
        metavar="DIFF",
        help="robustness contrast: report the seeds needed to detect a contrast of DIFF"
        " (in the metric's units) at 80 %% power (default: the observed contrast)",
    )
    parser.add_argument("--svg", action="store_true", help="SVG figures too")


def add_sweep_parsers(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """The sweep, compare and robustness sub-commands."""
    sweep = commands.add_parser("sweep", help="run a study: scenarios x axes x seeds")
    sweep.add_argument("study", type=Path, help="study YAML file (docs/sweeps.md)")
    add_backend_flags(sweep)
    sweep.add_argument(
        "--video-for", metavar="EXPR", help="write videos of the runs it selects, e.g. 'seed < 2'"
    )
    sweep.add_argument(
        "--shard",
        type=shard_arg,
        metavar="i/N",
        help="run only slice i of N (0 <= i < N) into OUT/shards/ (a job array's task;"
        " default in a SLURM array task: its SLURM_ARRAY_TASK_ID of SLURM_ARRAY_TASK_COUNT)",
    )
    compare = commands.add_parser("compare", help="figures and report of a sweep")
    compare.add_argument("sweep_dir", type=Path, help="a folder written by 'mresim sweep'")
    compare.add_argument(
        "--by",
        type=names,
        metavar="AXIS,AXIS",
        help="the arms: these axes (default every axis), e.g. strategy",
    )
    compare.add_argument(
        "--out", type=Path, help="folder for figures and report (default SWEEP_DIR/compare)"
    )
    add_compare_flags(compare)
    bench = commands.add_parser(
        "benchmark", help="run a benchmark suite, or --check a results folder"
    )
    bench.add_argument("suite", type=Path, nargs="?", help="suite YAML file (docs/benchmark.md)")
    bench.add_argument(
        "--check", type=Path, metavar="RESULTS", help="re-run and confirm a results folder"
    )
    bench.add_argument(
        "--sample", type=int, default=5, help="runs --check re-runs (0: all; default 5)"
    )
    add_backend_flags(bench)
    robust = commands.add_parser(
        "robustness", help="strategies x k random robot failures x seeds, swept and compared"
    )
    robust.add_argument("scenario", type=Path, help="scenario YAML file")
    robust.add_argument(
        "--failures",
        type=counts,
        default=[0, 1, 2],
        metavar="K,K",
        help="robots that fail per run (default 0,1,2)",
    )
    robust.add_argument(
        "--strategies",
        type=names,
        default=["frontier"],
        metavar="A,B",
        help="strategies to compare (default frontier)",
    )
    robust.add_argument("--seeds", type=positive_int, default=20, help="seeds 0..N-1 (default 20)")
    robust.add_argument("--steps", type=positive_int, help="step cap (default the scenario's)")
    robust.add_argument(
        "--fail-between",
        type=window,
        metavar="LOW,HIGH",
        help="failures happen between these fractions of the step cap (default 0.05,0.35)",
    )
    add_backend_flags(robust)
    add_compare_flags(robust)


def sweep_command(args: argparse.Namespace) -> int:
    """``mresim sweep``: run every missing run of a study; exit 1 if runs failed or were
    lost."""
    require_extra(args.dask is not None)
    from mresim_phys.sweeps.study import load_study

    study = load_study(args.study)
    text = args.study.read_text(encoding="utf-8")
    return sweep_and_report(study, args.study, text, args)


def sweep_and_report(study: Study, path: Path, text: str, args: argparse.Namespace) -> int:
    """Run the sweep, print its summary; 1 if some runs failed or were lost."""
    from mresim_phys.sweeps.runner import SweepOptions, run_sweep
    from mresim_phys.sweeps.shards import shard_from_env

    out = args.out or Path("sweeps") / study.name
    shard = getattr(args, "shard", None)
    if shard is None and hasattr(args, "shard"):  # `mresim sweep` in a SLURM array task
        shard = shard_from_env()
        if shard is not None and not args.quiet:
            print(f"mresim sweep: SLURM array task: shard {shard[0]}/{shard[1]}", file=sys.stderr)
    options = SweepOptions(
        out,
        args.workers,
        args.dask,
        getattr(args, "video_for", None),
        args.verbose,
        args.quiet,
        retry_failed=args.retry_failed,
        shard=shard,
    )
    result = run_sweep(study, path, text, options)
    if not args.quiet:
        print(result.summary())
    return 0 if result.complete else 1


def compare_command(args: argparse.Namespace) -> int:
    """``mresim compare``: figures and report of a sweep folder."""
    require_extra()
    from mresim_phys.sweeps.compare import compare_sweep

    paths, _ = compare_sweep(
        args.sweep_dir, args.by, args.metric, args.out, args.reference, args.svg, args.detect
    )
    for path in paths:
        print(path)
    return 0


def robustness_command(args: argparse.Namespace) -> int:
    """``mresim robustness``: build the failure study, sweep it, compare it; print the
    robustness contrast first."""
    require_extra(args.dask is not None)
    from mresim_phys.sweeps.compare import compare_sweep
    from mresim_phys.sweeps.report_tables import headline_lines
    from mresim_phys.sweeps.robustness import robustness_study
    from mresim_phys.sweeps.study import parse_study

    data, text = robustness_study(
        args.scenario, args.strategies, args.failures, args.seeds, args.steps, args.fail_between
    )
    study = parse_study(data, str(args.scenario))
    args.out = args.out or Path("sweeps") / study.name
    status = sweep_and_report(study, args.scenario, text, args)
    by = ["team.strategy", "failures"]
    paths, headline = compare_sweep(
        args.out, by, args.metric, None, args.reference, args.svg, args.detect
    )
    if headline is not None:
        print("\n".join(headline_lines(headline.section, headline.axis)))
    for path in paths:
        print(path)
    return status


def benchmark_command(args: argparse.Namespace) -> int:
    """``mresim benchmark``: run a suite into ``--out``, or ``--check`` a results folder
    (exit 1 when a run differs)."""
    from mresim_phys.errors import MresimError
    from mresim_phys.sweeps.benchmark import check_results, run_benchmark

    if args.check is not None:
        problems = check_results(args.check, max(args.sample, 0))
        for line in problems:
            print(f"mresim: benchmark check: {line}", file=sys.stderr)
        if not problems:
            print(f"{args.check}: every run checked gives the recorded metrics.csv")
        return 1 if problems else 0
    if args.suite is None:
        raise MresimError("benchmark: give a suite file, or --check RESULTS")
    require_extra(args.dask is not None)
    args.out = args.out or Path("benchmarks-out") / args.suite.stem
    return run_benchmark(args.suite, args.out, args)


SWEEP_COMMANDS = {
    "sweep": sweep_command,
    "benchmark": benchmark_command,
    "compare": compare_command,
    "robustness": robustness_command,
}
