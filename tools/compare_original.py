"""The original Java MRESim against ours on the original's own maps and team files (a script).

For every case (a map of the original's ``environments/`` and a team file: the original's
``config/`` file made for that map, or one of ours in ``tools/original_teams/``) it runs
the original (headless driver of ``/work/shared/original``, frontier greedy, PropModel1;
3 seeds) and ours (``mresim import-team``'s scenario, frontier, ``path_loss``; 5 seeds),
then prints one Markdown table per map: median (min-max) over seeds of the steps to 50 /
90 / 95 % explored and to 95 % known at base, the final fractions, the ratio ours /
original of the medians, and diagnostics: the median straight-line distance from a robot
to the frontier target it just picked, and the share of robot-steps in which a robot moved
less than 5 cells, while exploring and while going home (done, away from the base). Ours
stop when every robot is done and home, or when neither fraction gained 0.1 % in 300
steps; the original when all robots stand on the base pixel or nothing changed for
``--sat`` cycles. Maps are read from the original's tree at run time
(never copied); the raw outputs stay where ``--original-results`` / ``--ours-results``
say (the original's runs found there are read, not rerun)::

    python tools/compare_original.py --original /work/orig --original-results /work/orig-results
    python tools/compare_original.py --original /work/orig --case \\
        environments/hotel2.png=tools/original_teams/hotel2_8robots --seeds 1,2 --steps 800
    python tools/compare_original.py --original /work/orig --no-run-original \\
        --set 'team.strategy={name: frontier, params: {candidate_power: 2}}'

A map of our corpus (``maps/corpus``) runs once ``tools/original_png.py NAME --original
TREE`` has written it into the original's tree as ``environments/corpus/NAME.png`` with its
team file ``tools/original_teams/NAME_8robots`` (the Willow Garage map, kept aside, is one
of the default cases).

``--set PATH=VALUE`` changes a field of our scenarios (a dotted path, the value read as
YAML; repeatable); those runs go to a sub-folder of ``--ours-results`` named by the
changes, so they are never read as the default runs, and the original's runs are shared.

Denominator: every fraction is one of the original's ``totalArea`` T, all pixels of the
800x600 map that are not obstacles (first image band != 0; a smaller image is centred and
its margin is free), reachable or not. Our ``metrics.csv`` gives fractions of E, the
explorable cells (free cells some robot can see from where its body can go: every cell a
scan can mark free; ``Coverage.total``, summary.json's ``explorable_cells``, stored per run
in ``denominators.json``); a row's cell count is round(fraction * E), and that count / T
is the fraction the original would report (the original's joint area also counts every
free pixel some robot saw). Our map is read with threshold ``1e-6`` (only
pure black is wall, the original's rule), so both worlds have the same free pixels (the
header of each table gives the number of pixels the two rules disagree on). With
``--denominator explorable`` both sides are fractions of E instead (the milestones' own
denominator, docs/explorable.md): the original's joint and base pixel counts over E,
capped at E.

Censoring: a run that never reaches a threshold counts as later than every run that does;
the median is "never" when half the runs or more never reach it, and the range is over the
runs that did ("k/n" says how many). Team paths are looked up in the original's tree, then
in this repository, then in the current folder.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from mresim_phys.arg_types import add_settings

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))

from original_metrics import (  # noqa: E402  (a sibling script's module)
    CompareError,
    RunResult,
    base_pixel,
    censored_median,
    original_obstacles,
    original_total_area,
    over_explorable,
    read_json,
    read_original_output,
    read_ours,
    read_poslog,
    read_text,
    run_result,
)

Setting = tuple[str, Any]  # a --set PATH=VALUE
DRIVER = Path("/work/shared/original")
ORIGINAL_THRESHOLD = 1e-6  # our map threshold: only pure black is wall
STALL = 300  # our runs stop when neither fraction gained 0.1 % in this many steps
DEFAULT_CASES = (
    "environments/RAS2014/3.png=config/RAS2014/M3_L1_R8",
    "environments/RAS2014/4.png=config/RAS2014/M4_L1_R4",
    "environments/map_processed_resized.png=config/6_map_processed",
    "environments/12x12_rooms.png=config/8r_rooms",
    "environments/hotel2.png=tools/original_teams/hotel2_8robots",
    "environments/SSRR2014/1.png=config/SSRR2014/M1_L1_R2",
    "environments/hotel3.png=tools/original_teams/hotel3_8robots",  # kept aside: check only
    "environments/intel-map.png=tools/original_teams/intel-map_8robots",  # kept aside
    # kept aside; the image is written into the original's tree by tools/original_png.py
    "environments/corpus/willow_garage.png=tools/original_teams/willow_garage_8robots",
)


@dataclass(frozen=True)
class Case:
    """One map of the original's tree and the team file run on it."""

    key: str  # the map's path under environments/ without suffix, '/' as '-'
    map_path: Path
    team_path: Path


def case_of(spec: str, original: Path) -> Case:
    """``MAP=TEAM`` (paths as :func:`find_team` and the original's tree resolve them)."""
    map_text, sep, team_text = spec.partition("=")
    if not sep or not map_text or not team_text:
        raise CompareError(f"--case {spec!r}: give MAP=TEAM, e.g. {DEFAULT_CASES[0]}")
    map_path = original / map_text
    if not map_path.is_file():
        hint = " (a corpus map: write it with tools/original_png.py)" * ("corpus/" in map_text)
        raise CompareError(f"--case {spec!r}: no map {map_path} in the original's tree{hint}")
    key = str(Path(map_text).relative_to("environments").with_suffix("")).replace("/", "-")
    return Case(key, map_path, find_team(team_text, original))


def find_team(text: str, original: Path) -> Path:
    """The team file: absolute, or under the original's tree, this repository, the cwd."""
    for path in (Path(text), original / text, ROOT / text, Path.cwd() / text):
        if path.is_file():
            return path.resolve()
    raise CompareError(f"team file {text!r} found neither in {original} nor in {ROOT}")


def finished(out: Path) -> bool:
    """Whether ``out`` holds a whole run of the driver (it ends with its timing line)."""
    return out.is_file() and "# time1" in read_text(out)


def run_original(case: Case, seed: int, out: Path, args: argparse.Namespace) -> None:
    """Run the original with the driver (``run.sh``): its table into ``out``, the poslog
    next to it, the wall time as a last ``# wall_s=`` line."""
    out.parent.mkdir(parents=True, exist_ok=True)
    command = [
        "sh", str(args.driver / "run.sh"), str(args.original), "--team", str(case.team_path),
        "--map", str(case.map_path), "--seed", str(seed), "--cycles", str(args.steps),
        "--sat", str(args.sat), "--poslog", str(out.with_suffix(".pos.txt")),
    ]  # fmt: skip
    started = time.perf_counter()
    with open(out, "w", encoding="utf-8") as handle, open(out.with_suffix(".err"), "w") as err:
        subprocess.run(command, stdout=handle, stderr=err, check=False)
        handle.write(f"# wall_s={time.perf_counter() - started:.1f}\n")


def run_ours(
    case: Case, seed: int, steps: int, folder: Path, changes: Sequence[Setting] = ()
) -> Path:
    """Run our scenario of ``case`` (import-team's, read with the original's wall rule, with
    the ``--set`` ``changes``) unless ``folder`` has this run; store the two denominators
    next to its metrics."""
    from mresim_phys.output.session import run_session
    from mresim_phys.scenario.load import resolve_map_path, validate_scenario
    from mresim_phys.scenario.overrides import apply_overrides
    from mresim_phys.scenario.team_file import read_team_file
    from mresim_phys.sim import Simulation

    run_dir = folder / changed_folder(changes) / case.key / f"seed-{seed}"
    if (run_dir / "denominators.json").is_file():
        return run_dir
    data = read_team_file(case.team_path, str(case.map_path))
    data["map"]["threshold"] = ORIGINAL_THRESHOLD
    data |= {
        "name": case.key,
        "seed": seed,
        "steps": steps,
        "stop": {"all_done": True, "stalled_for": STALL},
        "render": {"video": False, "final_png": True, "log": True, "plots": False},
    }
    source = str(case.team_path)
    data = apply_overrides(data, dict(changes), source)
    sim = Simulation(resolve_map_path(validate_scenario(data, source), ROOT, source))
    counts = {
        "ours_explorable_cells": sim.coverage.total,
        "original_total_area": original_total_area(case.map_path),
        "pixels_the_wall_rules_disagree_on": rule_mismatch(sim.world.occupied, case.map_path),
    }
    run_session(sim, run_dir, overwrite=True)
    (run_dir / "denominators.json").write_text(json.dumps(counts, indent=2) + "\n")
    return run_dir


def changed_folder(changes: Sequence[Setting]) -> str:
    """The sub-folder of ``--ours-results`` for runs with these ``--set`` changes ('' for
    none), so a run with other settings is never read as this one's.

    >>> changed_folder([("team.radius", 1), ("team.strategy", {"name": "frontier"})])
    'set team.radius=1 team.strategy={name: frontier}'
    """
    if not changes:
        return ""
    text = " ".join(f"{path}={json.dumps(value, sort_keys=True)}" for path, value in changes)
    return "set " + text.replace('"', "").replace("/", "_")


def rule_mismatch(occupied: np.ndarray[Any, Any], image: Path) -> int:
    """Cells where our world's truth and the original's wall pixels disagree (-1: their
    sizes differ, a map smaller than 800x600)."""
    ours = np.asarray(occupied, dtype=bool)
    theirs = original_obstacles(image)
    if ours.shape != theirs.shape:
        return -1
    return int(np.count_nonzero(ours != theirs))


def spread(values: Sequence[float | None], digits: int = 0) -> str:
    """``median (min-max)`` with the count reached when some runs never got there."""
    if not values:
        return "no runs"
    reached = [v for v in values if v is not None]
    middle = censored_median(values)
    text = "never" if middle is None else f"{middle:.{digits}f}"
    if reached and (len(reached) > 1 or middle is None):
        text += f" ({min(reached):.{digits}f}-{max(reached):.{digits}f})"
    return text + ("" if len(reached) == len(values) else f" [{len(reached)}/{len(values)}]")


def ratio(ours: Sequence[float | None], original: Sequence[float | None]) -> str:
    """Ours / original of the censored medians ('-' when either is never)."""
    a, b = censored_median(ours), censored_median(original)
    return "-" if a is None or b is None or b == 0 else f"{a / b:.2f}"


Row = tuple[str, Callable[[RunResult], float | None], int]
ROWS: tuple[Row, ...] = (
    ("steps to 50 % explored", lambda r: r.milestones["e50"], 0),
    ("steps to 90 % explored", lambda r: r.milestones["e90"], 0),
    ("steps to 95 % explored", lambda r: r.milestones["e95"], 0),
    ("steps to 95 % at base", lambda r: r.milestones["b95"], 0),
    ("final explored", lambda r: r.final_explored, 3),
    ("final known at base", lambda r: r.final_base, 3),
    ("distance to a newly picked target (median, cells)", lambda r: r.goal_distance, 0),
    ("share of exploring robot-steps moving < 5 cells", lambda r: r.slow_exploring, 3),
    ("share of robot-steps going home moving < 5 cells", lambda r: r.slow_returning, 3),
    ("steps run", lambda r: r.steps, 0),
    ("wall time per run (s)", lambda r: r.wall_s, 0),
)


def case_table(case: Case, original: list[RunResult], ours: list[RunResult], note: str) -> str:
    """The Markdown table of one map."""
    lines = [
        f"### {case.key}",
        "",
        f"Team `{case.team_path.name}`; {note}",
        "",
        f"| measure | original ({len(original)} seeds) | ours ({len(ours)} seeds)"
        " | ours/original |",
        "|---|---|---|---|",
    ]
    for label, get, digits in ROWS:
        theirs, mine = [get(r) for r in original], [get(r) for r in ours]
        cells = (spread(theirs, digits), spread(mine, digits), ratio(mine, theirs))
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def overview(results: list[tuple[Case, list[RunResult], list[RunResult]]]) -> str:
    """One line per map: original and ours medians of the four milestones, and ratios."""
    lines = [
        "| map | explored 50 % orig / ours | 90 % orig / ours | 95 % orig / ours"
        " | base 95 % orig / ours |",
        "|---|---|---|---|---|",
    ]
    for case, original, ours in results:
        cells = []
        for key in ("e50", "e90", "e95", "b95"):
            theirs = [r.milestones[key] for r in original]
            mine = [r.milestones[key] for r in ours]
            cells.append(f"{spread(theirs)} / {spread(mine)} (x{ratio(mine, theirs)})")
        lines.append(f"| {case.key} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def seeds(text: str) -> list[int]:
    """A comma-separated list of seeds."""
    try:
        found = [int(s) for s in text.split(",") if s.strip()]
    except ValueError:
        found = []
    if not found:
        raise argparse.ArgumentTypeError(f"{text!r} is no list of integer seeds (1,2,3)")
    return found


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    """The command line."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--original", type=Path, required=True, help="the original's tree")
    parser.add_argument("--case", action="append", help="MAP=TEAM (default: the 9 cases)")
    parser.add_argument("--seeds", type=seeds, default=[1, 2, 3, 4, 5], help="ours")
    parser.add_argument("--original-seeds", type=seeds, default=[1, 2, 3])
    parser.add_argument("--steps", type=int, default=1500, help="step cap, ours and original")
    parser.add_argument("--sat", type=int, default=40, help="original: stop when flat this long")
    parser.add_argument("--original-results", type=Path, default=ROOT / "runs/original")
    parser.add_argument("--ours-results", type=Path, default=ROOT / "runs/compare-original")
    parser.add_argument("--driver", type=Path, default=DRIVER, help="the headless driver")
    parser.add_argument(
        "--no-run-original",
        dest="run_original",
        action="store_false",
        help="only read the original's whole runs found in --original-results",
    )
    add_settings(
        parser,
        "change a field of our scenarios, e.g. 'team.strategy={name: frontier, params:"
        " {candidate_power: 2}}' (repeatable; those runs go to a folder of their own)",
    )
    parser.add_argument("--out", type=Path, help="also write the tables to this file")
    parser.add_argument(
        "--denominator",
        choices=("original", "explorable"),
        default="original",
        help="fractions of the original's free pixels, or of our explorable cells (both sides)",
    )
    return parser.parse_args(argv)


def compare_case(
    case: Case, args: argparse.Namespace
) -> tuple[list[RunResult], list[RunResult], str]:
    """The original's runs and ours of one case (run where missing), and the table note."""
    home = base_pixel(case.team_path)
    runs = [run_ours(case, seed, args.steps, args.ours_results, args.set) for seed in args.seeds]
    counts = read_json(runs[0] / "denominators.json")
    explorable = args.denominator == "explorable"
    original = []
    for seed in args.original_seeds:
        out = args.original_results / case.key / f"seed-{seed}.txt"
        if not finished(out):
            if not args.run_original:
                continue
            run_original(case, seed, out, args)
        curve, wall = read_original_output(out)
        if explorable:
            curve = over_explorable(curve, int(counts["ours_explorable_cells"]))
        original.append(run_result(curve, read_poslog(out.with_suffix(".pos.txt"), home), wall))
    note = (
        f"the original's free pixels {counts['original_total_area']:,}, our explorable cells"
        f" {counts['ours_explorable_cells']:,}; the two wall rules disagree on"
        f" {counts['pixels_the_wall_rules_disagree_on']} pixels."
    )
    return original, [read_ours(run, explorable) for run in runs], note


def main(argv: list[str] | None = None) -> int:
    """Run (or read) every case, print the overview and one table per map."""
    from mresim_phys.errors import MresimError

    args = parse_args(argv)
    results, tables = [], []
    try:
        if not (args.original / "environments").is_dir():
            raise CompareError(f"--original {args.original}: no environments/ folder there")
        for case in [case_of(spec, args.original) for spec in args.case or DEFAULT_CASES]:
            original, ours, note = compare_case(case, args)
            results.append((case, original, ours))
            tables.append(case_table(case, original, ours, note))
    except (CompareError, MresimError) as exc:
        print(f"compare_original: {exc}", file=sys.stderr)
        return 2
    text = overview(results) + "\n" + "\n".join(tables)
    print(text)
    if args.out is not None:
        args.out.write_text(text, encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))
    sys.exit(main())
