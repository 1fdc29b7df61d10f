"""Benchmark of the whole step against an earlier commit, or the Java original, or both.

A commit that claims a speed-up measures it here: REV is checked out into a temporary git
worktree, and every round runs each (team size, thread count) once per build, each run in
its own fresh process (``mresim_phys.output.bench.time_team`` at the ``original`` preset:
the library, speed 10, laser 200, comm 200, its robots in rows of eight beside the base),
the builds alternating so that a busy spell of a shared machine hits both alike. It
prints, per configuration, each build's median over rounds of the per-run median ms per
step, their ratio, and the per-round ratios.

``--original TREE`` (default: the environment variable ``MRESIM_ORIGINAL``) names a built
tree of the Java original (v-spirin/MRESim with the headless driver compiled into its
``build/``: ``benchmarks/original_java.py``; the driver and its README in ``--driver``,
default ``/work/shared/original``) and times it beside this tree on the same machine, with
the same team: the original's own team file ``config/<N>robots_library`` (a count it has no
file for is skipped on this side). Every round runs the original (``run.sh TREE --team
config/<N>robots_library --map environments/library.png --seed <round> --cycles W+S``, W
and S the ``original`` preset's warm-up and timed steps; a run's figure is the median
``wall_ms`` of the S timed cycles, one ``simulationCycle`` each with the GUI's printing
sent to a null stream, and the median ``cpu_ms``, process CPU of all its threads) and ours
(``time_team`` with that team file as ``mresim import-team`` reads it: its starts, headings
and PropModel1 as ``path_loss``, the preset's run settings, on the preset's map, our redraw
of the original's library; once per thread count, each against the round's one run of the
original), the order alternating between rounds. It prints ours, the original's wall and
CPU medians over rounds, the ratio original / ours and the per-round ratios. With REV as
well it does both comparisons in the same rounds; an original tree that is not built, or a
machine without ``xvfb-run`` or ``java``, ends the script with status 2 and what is
missing.

Run from the repository root: ``python benchmarks/bench_against.py [REV] [--original TREE]
[--driver DIR] [--robots 8,16,32] [--threads 1,2] [--rounds 4] [--map PATH]`` (REV or
``--original``, or both). The original takes 1-1.7 s a cycle with 8 robots and 4.5-6 s
with 16 here (2 cores): a round of both sizes is 15-20 minutes.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

from original_java import DRIVER, require_built, team_file, time_original
from worktree import checked_out

ROOT = Path(__file__).resolve().parent.parent
SCRIPT = "bench_against.py"
ONE_RUN = """
import sys
from pathlib import Path
from mresim_phys.output.bench import PRESETS, time_team
robots, threads, map_path = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
team = {"team_file": Path(sys.argv[4])} if len(sys.argv) > 4 else {}
preset = PRESETS["original"]
path = Path(map_path) if map_path else preset.map_path
print(time_team(robots, path, preset.warmup, preset.steps, preset, (threads,), **team)[0].median_ms)
"""
Key = tuple[str, int, int]  # (side, robots, threads)
Run = Callable[[], dict[Key, float]]


def numbers(text: str) -> list[int]:
    """A comma-separated list of whole numbers."""
    return [int(part) for part in text.split(",") if part.strip()]


def median_ms(
    tree: Path, robots: int, threads: int, map_path: str, team: Path | None = None
) -> float:
    """One run's median ms per step with the code of ``tree`` (the preset's team, or the
    original's ``team`` file), in a fresh process."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    extra = [] if team is None else [str(team)]
    out = subprocess.run(
        [sys.executable, "-c", ONE_RUN, str(robots), str(threads), map_path, *extra],
        cwd=tempfile.gettempdir(),  # not the repository: PYTHONPATH decides the build
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    return float(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("rev", nargs="?", help="the commit to compare with (e.g. HEAD~5)")
    parser.add_argument(
        "--original",
        type=Path,
        default=os.environ.get("MRESIM_ORIGINAL") or None,
        help="a built tree of the Java original (default: $MRESIM_ORIGINAL)",
    )
    parser.add_argument("--driver", type=Path, default=DRIVER, help="the headless driver")
    parser.add_argument("--robots", type=numbers, default=[8, 16, 32])
    parser.add_argument("--threads", type=numbers, default=[1, 2])
    parser.add_argument("--rounds", type=int, default=4)
    parser.add_argument("--map", default="", help="map image (default: the preset's)")
    args = parser.parse_args()
    if args.rev is None and args.original is None:
        parser.error("give REV, --original TREE (or set MRESIM_ORIGINAL), or both")
    if args.original is not None:
        from_flag = any(a.startswith("--original") for a in sys.argv[1:])
        named_by = "--original" if from_flag else "MRESIM_ORIGINAL"
        require_built(args.original.resolve(), args.driver, named_by, SCRIPT)
        args.original = args.original.resolve()
    if args.rev is None:
        compare(None, args)
        return
    with checked_out(ROOT, args.rev, SCRIPT) as old:
        compare(old, args)


def original_teams(args: argparse.Namespace) -> dict[int, Path]:
    """The original's team file of each team size it has one for (the others said)."""
    if args.original is None:
        return {}
    teams = {}
    for robots in args.robots:
        path = team_file(args.original, robots)
        if path is None:
            print(f"the original has no config/{robots}robots_library: {robots} robots skipped")
        else:
            teams[robots] = path
    return teams


def round_runs(
    old: Path | None, robots: int, team: Path | None, seed: int, args: argparse.Namespace
) -> list[Run]:
    """The runs of one team size in one round: before / now per thread count, then the
    original and ours with its team file."""
    from mresim_phys.output.bench import PRESETS

    def ours(side: str, tree: Path, threads: int, team: Path | None = None) -> Run:
        return lambda: {(side, robots, threads): median_ms(tree, robots, threads, args.map, team)}

    def java(team: Path) -> Run:
        preset = PRESETS["original"]

        def run() -> dict[Key, float]:
            times = time_original(
                args.original, args.driver, team, seed, preset.warmup, preset.steps
            )
            return {("original", robots, 0): times.wall_ms, ("cpu", robots, 0): times.cpu_ms}

        return run

    runs = []
    if old is not None:
        for threads in args.threads:
            runs += [ours("before", old, threads), ours("now", ROOT, threads)]
    if team is not None:
        runs += [java(team), *(ours("ours", ROOT, t, team) for t in args.threads)]
    return runs


def compare(old: Path | None, args: argparse.Namespace) -> None:
    """Alternate the runs over the rounds and print the medians and ratios."""
    teams = original_teams(args)
    times: dict[Key, list[float]] = {}
    for k in range(args.rounds):
        for robots in args.robots:
            runs = round_runs(old, robots, teams.get(robots), k + 1, args)
            for run in runs if k % 2 == 0 else runs[::-1]:
                for key, ms in run().items():
                    times.setdefault(key, []).append(ms)
    configs = [(r, t) for r in args.robots for t in args.threads]
    if old is not None:
        print(f"ms per step, {args.rev} (before) and this tree (now), {args.rounds} rounds")
        print(" robots threads   before      now  now/before  per round")
        for robots, threads in configs:
            before, now = times["before", robots, threads], times["now", robots, threads]
            rounds = " ".join(f"{b / a:.2f}" for a, b in zip(before, now, strict=True))
            a, b = statistics.median(before), statistics.median(now)
            print(f"{robots:>7} {threads:>7} {a:8.2f} {b:8.2f} {b / a:11.2f}  {rounds}")
    if teams:
        print_original(times, [(r, t) for r, t in configs if r in teams], args)


def print_original(
    times: dict[Key, list[float]], configs: list[tuple[int, int]], args: argparse.Namespace
) -> None:
    """The table of ours against the original: medians over rounds and the ratios."""
    print(
        f"ms per step: this tree (ours) and the Java original {args.original} (wall and CPU"
        f" ms per cycle), the original's team files config/<N>robots_library, {args.rounds}"
        " rounds"
    )
    print(" robots threads     ours  original  orig cpu  original/ours  per round")
    for robots, threads in configs:
        ours, java = times["ours", robots, threads], times["original", robots, 0]
        rounds = " ".join(f"{b / a:.1f}" for a, b in zip(ours, java, strict=True))
        a, b, cpu = (statistics.median(v) for v in (ours, java, times["cpu", robots, 0]))
        print(f"{robots:>7} {threads:>7} {a:8.2f} {b:9.1f} {cpu:9.1f} {b / a:14.1f}  {rounds}")


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))  # this tree's package for the preset's steps
    main()
