"""Corpus runs (a script over the sweep layer's API): teams on every real building map.

``python tools/corpus.py run --maps all --strategies frontier,role_based,utility_return,
hungarian --sizes 4,8 --seeds 3 --steps 600 --out DIR`` builds one scenario per (map,
strategy, team size, seed) from ``maps/corpus/corpus.yaml`` (``DIR/scenarios/*.yaml``:
each runs alone with ``mresim run``), runs them in-process as ``mresim run`` does (a
process pool of ``--jobs``), and writes ``DIR/corpus.csv`` (one row per run: milestones,
final explored and known at base, stop reason, steps, robot states at the end, run
health with the robots that worked fruitlessly, how the run breaks the invariant) and
``DIR/corpus.md`` (per map, the medians over seeds of each strategy and size; the runs
that break the invariant).

The invariant (``corpus_report.violations``, asserted by ``tests/test_corpus.py``'s slow
test): a run explores at least 95 % of the explorable area, and no explorer idles more than
20 steps while its own map holds frontier cells it can reach (docs/run-health.md).
``python tools/corpus.py check`` checks the index: files, licences, starts.

Robots are of the original MRESim's kind (radius 0.5 cells, wall margin 0.5) and metric
settings are turned into cells with each map's resolution: an 8 m laser over 180 degrees,
0.5 m per step, path-loss radio whose reference range is 20 m (walls weaken it).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import traceback
from collections import Counter
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from corpus_report import MILESTONES, report, violations, write_csv  # noqa: E402  (sibling)

ROOT = HERE.parent
INDEX = ROOT / "maps" / "corpus" / "corpus.yaml"
STRATEGIES = ("frontier", "role_based", "utility_return", "hungarian")
SENSOR_M, STEP_M, COMM_M = 8.0, 0.5, 20.0  # laser range, distance per step, radio reference
RADIUS, WALL_MARGIN = 0.5, 0.5  # cells: the original's point-like robots
MIN_CLEARANCE = 4.0  # cells from a start cell's boundary to the nearest obstacle cell
REQUIRED = ("name", "file", "kind", "source", "licence", "modified", "base", "starts")


@dataclass(frozen=True)
class CorpusMap:
    """One entry of the corpus index (positions are cells: x = column, y = row)."""

    name: str
    file: Path
    kind: str
    source: str
    licence: str
    modified: bool
    resolution: float
    base: tuple[int, int]
    starts: tuple[tuple[int, int], ...]


def load_index(path: Path = INDEX) -> list[CorpusMap]:
    """The maps of the corpus index; ValueError naming the entry and field if one is bad."""
    data = yaml.safe_load(path.read_text(encoding="utf-8"))
    return [_entry(path, raw) for raw in data["maps"]]


def _entry(path: Path, raw: dict[str, Any]) -> CorpusMap:
    """One index entry, checked for its required fields."""
    missing = [k for k in REQUIRED if raw.get(k) in (None, "")]
    if missing:
        raise ValueError(f"{path}: map {raw.get('name', '?')!r} has no {', '.join(missing)}")
    return CorpusMap(
        name=str(raw["name"]),
        file=path.parent / str(raw["file"]),
        kind=str(raw["kind"]),
        source=str(raw["source"]),
        licence=str(raw["licence"]),
        modified=bool(raw["modified"]),
        resolution=float(raw["resolution"]),
        base=(int(raw["base"][0]), int(raw["base"][1])),
        starts=tuple((int(x), int(y)) for x, y in raw["starts"]),
    )


def select(maps: Sequence[CorpusMap], names: str) -> list[CorpusMap]:
    """The maps named in ``names`` (comma-separated, or 'all'); ValueError on an unknown one."""
    if names == "all":
        return list(maps)
    known = {m.name: m for m in maps}
    wanted = [n.strip() for n in names.split(",") if n.strip()]
    unknown = [n for n in wanted if n not in known]
    if unknown:
        raise ValueError(f"unknown corpus maps {unknown}; the corpus has {sorted(known)}")
    return [known[n] for n in wanted]


def check_map(entry: CorpusMap) -> list[str]:
    """Problems with a map's positions: off the map, on or near a wall (closer than
    :data:`MIN_CLEARANCE`), or not all in one connected free region."""
    from scipy import ndimage

    from mresim_phys.scenario.readers import load_ros_map
    from mresim_phys.world.maps import free_components_mask

    occupied = load_ros_map(entry.file).occupied
    room = np.asarray(ndimage.distance_transform_edt(np.pad(~occupied, 1)))[1:-1, 1:-1] - 0.5
    points = [entry.base, *entry.starts]
    rows, cols = occupied.shape
    outside = [p for p in points if not (0 <= p[0] < cols and 0 <= p[1] < rows)]
    if outside:
        return [f"{entry.name}: {outside} outside the {cols} x {rows} map"]
    problems = [
        f"{entry.name}: ({x}, {y}) is {room[y, x]:.1f} cells from a wall"
        for x, y in points
        if room[y, x] < MIN_CLEARANCE
    ]
    if not problems:
        together = free_components_mask(occupied, [(x + 0.5, y + 0.5) for x, y in points])
        base_region = free_components_mask(occupied, (entry.base[0] + 0.5, entry.base[1] + 0.5))
        if together.sum() != base_region.sum():
            problems.append(f"{entry.name}: not every start is in the base's free region")
    return problems


@dataclass(frozen=True)
class Job:
    """One run of the matrix."""

    entry: CorpusMap
    strategy: str
    size: int
    seed: int
    steps: int
    radii: tuple[float, ...] = (RADIUS,)

    @property
    def name(self) -> str:
        """The run's (and its scenario's) name."""
        return f"{self.entry.name}-{self.strategy}-n{self.size}-s{self.seed}"


def team_settings(resolution: float) -> dict[str, Any]:
    """Team defaults in cells for a map of ``resolution`` metres per cell."""
    comm = round(COMM_M / resolution)
    return {
        "speed": round(STEP_M / resolution, 2),
        "radius": RADIUS,
        "wall_margin": WALL_MARGIN,
        "sensor": {"range": round(SENSOR_M / resolution), "fov_deg": 180, "rays": 181},
        "comm_range": comm,
    }


def robots(job: Job) -> list[dict[str, Any]]:
    """The team: robots at the index's starts (cell centres), radii cycled from
    ``job.radii``; for role_based, relay / explorer pairs (the last robot of an odd team
    explores alone)."""
    starts = job.entry.starts
    if job.size > len(starts):
        raise ValueError(f"{job.entry.name} has {len(starts)} starts, not {job.size}")
    team = []
    for k, (x, y) in enumerate(starts[: job.size]):
        robot: dict[str, Any] = {"name": f"R{k + 1}", "start": [x + 0.5, y + 0.5]}
        robot["radius"] = job.radii[k % len(job.radii)]
        team.append(robot)
    if job.strategy == "role_based":
        for k in range(0, job.size - 1, 2):
            team[k].update(role="relay", parent="base")
            team[k + 1]["parent"] = team[k]["name"]
    return team


def scenario_data(job: Job) -> dict[str, Any]:
    """The scenario of ``job`` as YAML data (the map path is absolute)."""
    settings = team_settings(job.entry.resolution)
    bx, by = job.entry.base
    return {
        "name": job.name,
        "seed": job.seed,
        "steps": job.steps,
        "stop": {"known_at_base": 0.95},
        "map": {"ros": str(job.entry.file.resolve())},
        "base_station": {"position": [bx + 0.5, by + 0.5], "comm_range": settings["comm_range"]},
        "team": {**settings, "strategy": job.strategy},
        "robots": robots(job),
        "communication": {"model": "path_loss"},
        "render": {"log": False, "plots": False, "final_png": True},
    }


def run_job(job: Job, out: Path) -> dict[str, Any]:
    """Write and run ``job``'s scenario as ``mresim run`` does; its CSV row (a run that
    raises gives a row with the error and no results)."""
    from mresim_phys.output.session import run_session
    from mresim_phys.output.signals import StopRequest
    from mresim_phys.sim import Simulation

    scenario = out / "scenarios" / f"{job.name}.yaml"
    scenario.parent.mkdir(parents=True, exist_ok=True)
    scenario.write_text(yaml.safe_dump(scenario_data(job), sort_keys=False), encoding="utf-8")
    folder = out / "runs" / job.name
    started = time.process_time()
    try:
        sim = Simulation.from_yaml(scenario)
        run_session(sim, folder, overwrite=True, stop=StopRequest(False))
    except Exception as exc:
        (out / "errors").mkdir(exist_ok=True)
        (out / "errors" / f"{job.name}.log").write_text(traceback.format_exc(), encoding="utf-8")
        failed = {**job_fields(job), "error": f"{type(exc).__name__}: {exc}"[:300]}
        return {**failed, "invariant": "; ".join(violations(failed))}
    summary = json.loads((folder / "summary.json").read_text(encoding="utf-8"))
    row = {**job_fields(job), **summary_fields(summary), **idle_fields(summary)}
    return {**row, "invariant": "; ".join(violations(row)), "cpu_s": cpu_since(started)}


def cpu_since(started: float) -> float:
    """Process CPU seconds since ``started``."""
    return round(time.process_time() - started, 1)


def idle_fields(summary: dict[str, Any]) -> dict[str, Any]:
    """The robots' idle steps with reachable frontier cells (the worst one and who). A
    relay waiting at a meeting point for its explorer is ``waiting``, not idle
    (``knowledge/health.py``), so every robot counts, relays too."""
    health = summary.get("health", {}).get("robots", {})
    idle = {n: int(h["idle_with_frontier"]) for n, h in health.items()}
    worst = max(idle, key=lambda n: idle[n], default="")
    if not idle.get(worst):
        return {"robot_idle_with_frontier": 0, "idlest_robot": ""}
    return {"robot_idle_with_frontier": idle[worst], "idlest_robot": worst}


def job_fields(job: Job) -> dict[str, Any]:
    """The columns that name a run."""
    radii = "/".join(f"{r:g}" for r in job.radii)
    return {
        "map": job.entry.name,
        "kind": job.entry.kind,
        "strategy": job.strategy,
        "size": job.size,
        "seed": job.seed,
        "radii": radii,
        "error": "",
    }


def summary_fields(summary: dict[str, Any]) -> dict[str, Any]:
    """The summary.json fields that matter, flattened for a CSV row."""
    row: dict[str, Any] = {
        "steps": summary["steps"],
        "stop_reason": summary["stop_reason"],
        "final_explored": round(summary["final_explored"], 4),
        "final_known_at_base": round(summary["final_known_at_base"], 4),
    }
    for level in MILESTONES:
        row[f"explored_{level}_at"] = summary["steps_to_explored"].get(level)
        row[f"base_{level}_at"] = summary["steps_to_known_at_base"].get(level)
    states = {name: r["state"] for name, r in summary["robots"].items()}
    counts = Counter(states.values())
    for state in ("active", "done", "error", "failed"):
        row[f"robots_{state}"] = counts.get(state, 0)
    row["robot_states"] = " ".join(f"{name}:{state}" for name, state in states.items())
    row["alive"] = summary.get("alive")
    health = summary.get("health", {})
    row["robots_idle_with_frontier"] = health.get("robots_idle_with_frontier")
    row["idle_robot_steps"] = health.get("idle_robot_steps")
    row["stuck_robot_steps"] = health.get("stuck_robot_steps")
    row["robots_fruitless"] = health.get("robots_fruitless")
    row["fruitless_robot_steps"] = health.get("fruitless_robot_steps")
    row["final_explored_connected"] = summary.get("final_explored_connected")
    return row


def make_jobs(
    maps: Sequence[CorpusMap],
    strategies: Sequence[str],
    sizes: Sequence[int],
    seeds: Iterable[int],
    steps: int,
    radii: tuple[float, ...] = (RADIUS,),
) -> list[Job]:
    """Every (map, strategy, size, seed) combination, in that order."""
    seeds = list(seeds)
    small = [m.name for m in maps if len(m.starts) < max(sizes)]
    if small:
        raise ValueError(f"maps {small} have fewer starts than a team of {max(sizes)}")
    return [
        Job(entry, strategy, size, seed, steps, radii)
        for entry in maps
        for strategy in strategies
        for size in sizes
        for seed in seeds
    ]


def _run_one(args: tuple[Job, Path]) -> dict[str, Any]:
    return run_job(*args)


def run_all(
    jobs: Sequence[Job],
    out: Path,
    workers: int = 2,
    progress: Callable[[dict[str, Any]], None] | None = None,
) -> list[dict[str, Any]]:
    """Run ``jobs`` (``workers`` processes; 1 runs them here); their rows, in job order."""
    out.mkdir(parents=True, exist_ok=True)
    tasks = [(job, out) for job in jobs]
    rows: list[dict[str, Any]] = []
    if workers <= 1:
        results: Iterable[dict[str, Any]] = map(_run_one, tasks)
        for row in results:
            rows.append(row)
            if progress:
                progress(row)
        return rows
    with ProcessPoolExecutor(max_workers=workers) as pool:
        for row in pool.map(_run_one, tasks):
            rows.append(row)
            if progress:
                progress(row)
    return rows


def positive_ints(text: str) -> list[int]:
    """A comma-separated list of positive integers (argparse type)."""
    values = [int(v) for v in text.split(",") if v.strip()]
    if not values or min(values) < 1:
        raise argparse.ArgumentTypeError(f"expected positive integers, got {text!r}")
    return values


def parse_args(argv: Sequence[str] | None) -> argparse.Namespace:
    """The command line."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="run the matrix and write corpus.csv and corpus.md")
    run.add_argument("--maps", default="all", help="'all' or comma-separated map names")
    run.add_argument("--strategies", default=",".join(STRATEGIES))
    run.add_argument("--sizes", type=positive_ints, default=[4, 8], help="team sizes")
    run.add_argument("--seeds", type=int, default=3, help="seeds 1..N per combination")
    run.add_argument("--steps", type=int, default=600)
    run.add_argument("--radii", default=f"{RADIUS}", help="robot radii, cycled: e.g. 0.5,1.0")
    run.add_argument("--jobs", type=int, default=2, help="worker processes")
    run.add_argument("--out", type=Path, required=True)
    sub.add_parser("check", help="check the index: files, licences, start positions")
    return parser.parse_args(argv)


def check_command() -> int:
    """``check``: every index entry's file loads and its positions are valid."""
    problems: list[str] = []
    for entry in load_index():
        found = check_map(entry)
        problems += found
        print(f"{entry.name:20s} {'ok' if not found else 'BAD'}")
    for line in problems:
        print(line, file=sys.stderr)
    return 1 if problems else 0


def known_strategies(text: str) -> list[str]:
    """The comma-separated strategy names of ``text``; ValueError on an unregistered one."""
    from mresim_phys.strategies import STRATEGIES as REGISTRY

    names = [s.strip() for s in text.split(",") if s.strip()]
    unknown = [n for n in names if n not in REGISTRY.names()]
    if unknown or not names:
        raise ValueError(f"unknown strategies {unknown}; choose from {REGISTRY.names()}")
    return names


def run_command(args: argparse.Namespace) -> int:
    """``run``: the matrix, the CSV and the report."""
    maps = select(load_index(), args.maps)
    strategies = known_strategies(args.strategies)
    radii = tuple(float(r) for r in args.radii.split(","))
    jobs = make_jobs(maps, strategies, args.sizes, range(1, args.seeds + 1), args.steps, radii)
    done = 0

    def progress(row: dict[str, Any]) -> None:
        nonlocal done
        done += 1
        result = row["error"] or f"explored {row['final_explored']:.3f} in {row['steps']} steps"
        run = f"{row['map']} {row['strategy']} n{row['size']} s{row['seed']}"
        print(f"[{done}/{len(jobs)}] {run}: {result}", flush=True)

    rows = run_all(jobs, args.out, args.jobs, progress)
    write_csv(rows, args.out / "corpus.csv")
    (args.out / "corpus.md").write_text(report(rows), encoding="utf-8")
    print(f"wrote {args.out / 'corpus.csv'} and {args.out / 'corpus.md'}")
    return 1 if any(r["error"] for r in rows) else 0


def main(argv: Sequence[str] | None = None) -> int:
    """Run a command; 2 on a bad argument."""
    args = parse_args(argv)
    try:
        return check_command() if args.command == "check" else run_command(args)
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))
    sys.exit(main())
