"""Benchmark (output edge): ``mresim bench``, median milliseconds per step and where they go.

Builds a frontier-exploration team of 4, 8 and 16 robots (or any size) from a preset
(:data:`PRESETS`): ``office`` (speed 3, radius 2, range 100, disk comm 150 on the 800x600
office floor), or the original MRESim's settings (speed 10, laser 200, comm 200, point-like
robots of radius 0.5) on its ``library`` or ``rooms`` layout, or those settings with disk
comm on a ``campus``, a generated 4000 x 4000 building (``output/campus.py``); runs warm-up
steps, then times each step and reports the median and 90th percentile per step and the median
cost of each phase per step (sensing = ray casting, mapping = map updates,
planning = strategy decisions incl. frontiers and distance fields,
communication = links and merges, metrics; "motion" is the rest: path following
and swept-circle checks). Medians, not means: the machine may be shared.

``--threads 1,2`` times one run per thread count (``simulation.threads``), the runs
stepped in turn in one process; with threads the phase columns add up every thread's time.

Robots start in rows of eight beside the base (:func:`row_starts`); a start that would
touch a wall, and every robot past the rows' room, goes to the nearest free spot (every
``SPACING`` cells, clear of walls by the robot's radius, reachable from the first start)
by a search over the map (:func:`team_starts`), so teams of any size fit. Or the team is
one of the original MRESim's team files, as ``mresim import-team`` reads it (its starts,
headings, ranges and PropModel1 as ``path_loss``; :func:`team_file_scenario`), for timing
beside the original itself (``benchmarks/bench_against.py --original``).
"""

from __future__ import annotations

import statistics
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from time import perf_counter
from typing import Any, Literal

import numpy as np

from mresim_phys.errors import MresimError
from mresim_phys.output.campus import campus_map
from mresim_phys.scenario.load import validate_scenario
from mresim_phys.scenario.readers import load_image_map
from mresim_phys.scenario.team_file import read_team_file
from mresim_phys.sim import PHASES, Simulation
from mresim_phys.types import BoolGrid
from mresim_phys.world.maps import connected_to, seed_cells
from mresim_phys.world.space import World

PACKAGE_DATA = Path(__file__).resolve().parent.parent / "data"  # installed with the package
SPACING = 8  # cells between neighbouring starts


@dataclass(frozen=True)
class Preset:
    """A benchmark setting: map, base, where the team starts, the team's fields and the
    steps warmed up and timed by default."""

    name: str
    map_file: str
    base: tuple[float, float]
    start: tuple[float, float]
    team: dict[str, Any]
    warmup: int
    steps: int
    communication: dict[str, Any] | None = None  # the scenario's, when not the default
    make_map: Callable[[], Path] | None = None  # draws the map (not shipped) on first use

    @property
    def map_path(self) -> Path:
        """The preset's map, shipped with the package (or drawn and cached: ``campus``)."""
        return self.make_map() if self.make_map is not None else PACKAGE_DATA / self.map_file

    @property
    def radius(self) -> float:
        """The robots' body radius."""
        return float(self.team["radius"])


ORIGINAL_TEAM = {  # the original MRESim's comparison settings (scenarios 11-13)
    "speed": 10,
    "radius": 0.5,
    "wall_margin": 0.5,
    "sensor": {"range": 200},
    "comm_range": 200,
}
PRESETS = {
    "office": Preset(
        "office",
        "office.png",
        (25.0, 300.0),
        (40.0, 300.0),
        {"speed": 3, "radius": 2.0, "sensor": {"range": 100}, "comm_range": 150},
        50,
        200,
    ),
    # the exploring phase: library teams of 8-16 reach 95 % in 110-170 steps
    "original": Preset(
        "original", "library.png", (380.5, 520.5), (390.5, 520.5), ORIGINAL_TEAM, 10, 100
    ),
    "rooms": Preset("rooms", "rooms.png", (370.5, 520.5), (350.5, 520.5), ORIGINAL_TEAM, 10, 100),
    # issue 37's scale: a 4000 x 4000 building (output/campus.py), disk comm 200, laser 200
    "campus": Preset(
        "campus", "", (4.5, 4.5), (9.5, 4.5), ORIGINAL_TEAM, 5, 20, {"model": "disk"}, campus_map
    ),
}
OFFICE = PRESETS["office"]
DEFAULT_MAP = OFFICE.map_path


@dataclass(frozen=True)
class BenchResult:
    """Per-step timings of one team size at one thread count (milliseconds)."""

    robots: int
    median_ms: float
    p90_ms: float
    phase_ms: dict[str, float]
    explored: float
    threads: int | str = 1
    strategy: str = "frontier"


Point = tuple[float, float]


def row_starts(robots: int, start: Point = OFFICE.start) -> list[Point]:
    """The preferred starts: rows of eight, ``SPACING`` apart, from ``start``."""
    x, y = start
    return [(x + SPACING * (i % 8), y + SPACING * (i // 8) - SPACING / 2) for i in range(robots)]


def spots_near(occupied: BoolGrid, origin: tuple[float, float]) -> list[tuple[float, float]]:
    """Points every ``SPACING`` cells on free cells reachable from ``origin``, nearest first."""
    reachable = connected_to(~occupied, seed_cells([list(origin)], occupied.shape))
    rows, cols = np.nonzero(reachable[::SPACING, ::SPACING])
    xs, ys = cols * SPACING + origin[0] % SPACING, rows * SPACING + origin[1] % SPACING
    order = np.argsort(np.hypot(xs - origin[0], ys - origin[1]), kind="stable")
    return [(float(xs[k]), float(ys[k])) for k in order]


def team_starts(
    robots: int, occupied: BoolGrid, preset: Preset = OFFICE
) -> list[tuple[float, float]]:
    """``robots`` starts clear of walls and ``SPACING`` apart: the rows first, then the free
    spots nearest the first start; MresimError if the map has no room for them all."""
    world = World(occupied, [])
    chosen: list[tuple[float, float]] = []

    def fits(p: tuple[float, float]) -> bool:
        far = all(abs(p[0] - q[0]) >= SPACING or abs(p[1] - q[1]) >= SPACING for q in chosen)
        return far and not world.overlaps_wall(p, preset.radius)

    chosen += [p for p in row_starts(robots, preset.start) if fits(p)]
    if len(chosen) < robots:
        for p in spots_near(occupied, preset.start):
            if fits(p):
                chosen.append(p)
                if len(chosen) == robots:
                    break
    if len(chosen) < robots:
        raise MresimError(
            f"the benchmark map has room for {len(chosen)} robots {SPACING} cells apart near"
            f" {list(preset.start)}, not {robots}; give fewer --robots or another --map."
        )
    return chosen[:robots]


RELAY_STRATEGIES = ("role_based", "role_switch")  # teams paired into explorer / relay


def team_scenario(
    robots: int,
    map_path: Path,
    steps: int,
    preset: Preset = OFFICE,
    threads: int | Literal["auto"] = 1,
    strategy: str = "frontier",
) -> dict[str, Any]:
    """A team of ``robots`` (``strategy``: the preset's, frontier; ``name:rendezvous`` for a
    relay strategy's rendezvous) starting beside the base (:func:`team_starts`); for the
    relay strategies (``role_based``, ``role_switch``) the robots pair up in order, the first
    of each two a relay under the base, the second its explorer."""
    starts = team_starts(robots, load_image_map(map_path).occupied, preset)
    team = [{"name": f"R{i}", "start": list(s)} for i, s in enumerate(starts)]
    if strategy.partition(":")[0] in RELAY_STRATEGIES:
        for i, robot in enumerate(team):
            pair = {"parent": f"R{i - 1}"} if i % 2 else {"role": "relay", "parent": "base"}
            robot.update(pair)
    return {
        "name": f"bench-{robots}",
        **run_settings(steps, threads),
        "map": {"image": str(map_path)},
        "base_station": {"position": list(preset.base), "comm_range": preset.team["comm_range"]},
        "team": {**preset.team, "strategy": strategy_spec(strategy)},
        "robots": team,
        **({"communication": preset.communication} if preset.communication else {}),
    }


def strategy_spec(strategy: str) -> str | dict[str, Any]:
    """The scenario's strategy of ``name`` or ``name:rendezvous``."""
    name, _, rendezvous = strategy.partition(":")
    return {"name": name, "params": {"rendezvous": rendezvous}} if rendezvous else name


def run_settings(steps: int, threads: int | Literal["auto"]) -> dict[str, Any]:
    """A timed run's fields: seed 1, ``steps`` steps, no early stop."""
    return {
        "seed": 1,
        "steps": steps,
        "stop": {"all_done": False, "stalled_for": None},
        "simulation": {"threads": threads},
    }


def team_file_scenario(
    team_file: Path,
    map_path: Path,
    steps: int,
    threads: int | Literal["auto"] = 1,
    strategy: str = "frontier",
) -> dict[str, Any]:
    """The original MRESim's team file on ``map_path`` as ``mresim import-team`` reads it
    (its base, starts, headings, ranges and PropModel1 as ``path_loss``), run as
    :func:`team_scenario`'s teams are."""
    data = read_team_file(team_file, str(map_path))
    data["team"]["strategy"] = strategy_spec(strategy)
    return data | run_settings(steps, threads)


class StepTimes:
    """One timed simulation's per-step totals and phase costs (seconds)."""

    def __init__(self, sim: Simulation) -> None:
        self.sim = sim
        self.totals: list[float] = []
        self.phases: dict[str, list[float]] = {name: [] for name in (*PHASES, "motion")}

    def step(self) -> None:
        """Time one step."""
        sim = self.sim
        before = dict(sim.phase_times)
        started = perf_counter()
        sim.step()
        total = perf_counter() - started
        self.totals.append(total)
        spent = {name: sim.phase_times[name] - before[name] for name in PHASES}
        for name, seconds in spent.items():
            self.phases[name].append(seconds)
        self.phases["motion"].append(max(total - sum(spent.values()), 0.0))

    def result(self, robots: int, threads: int | str, strategy: str) -> BenchResult:
        """Medians in milliseconds."""
        return BenchResult(
            robots,
            1e3 * statistics.median(self.totals),
            1e3 * float(np.percentile(self.totals, 90)),
            {name: 1e3 * statistics.median(v) for name, v in self.phases.items()},
            self.sim.record.explored,
            threads,
            strategy,
        )


def time_team(
    robots: int,
    map_path: Path,
    warmup: int,
    measured: int,
    preset: Preset = OFFICE,
    threads: Sequence[int | Literal["auto"]] = (1,),
    strategies: Sequence[str] = ("frontier",),
    team_file: Path | None = None,
) -> list[BenchResult]:
    """Run warm-up steps, then time ``measured`` steps of a team of ``robots`` (the preset's
    team, or the original's ``team_file``: :func:`team_file_scenario`, with ``robots``
    robots), once per (strategy, thread count): the runs step in turn, alternating which
    goes first, so a busy spell on a shared machine hits them alike."""
    variants = [(name, count) for name in strategies for count in threads]
    timers = []
    for name, count in variants:
        steps = warmup + measured
        if team_file is None:
            data = team_scenario(robots, map_path, steps, preset, count, name)
        else:
            data = team_file_scenario(team_file, map_path, steps, count, name)
            if len(data["robots"]) != robots:
                raise MresimError(
                    f"team file {team_file} has {len(data['robots'])} robots, not {robots}"
                )
        timers.append(StepTimes(Simulation(validate_scenario(data))))
    for timer in timers:
        for _ in range(warmup):
            timer.sim.step()
    for k in range(measured):
        for timer in timers if k % 2 == 0 else timers[::-1]:
            timer.step()
    return [
        timer.result(robots, count, name)
        for timer, (name, count) in zip(timers, variants, strict=True)
    ]


def report(results: Sequence[BenchResult], map_path: Path, preset: Preset = OFFICE) -> str:
    """The results as a text table."""
    names = [*PHASES, "motion"]
    head = f"{'strategy':>14} {'robots':>6} {'threads':>7} {'median':>8} {'p90':>8} "
    head += f"{'per robot':>9} " + " ".join(f"{n:>13}" for n in names)
    lines = [f"mresim bench --preset {preset.name}: teams on {map_path.name}, ms per step", head]
    for r in results:
        split = " ".join(f"{r.phase_ms[n]:13.2f}" for n in names)
        per_robot = r.median_ms / r.robots
        times = f"{r.median_ms:8.2f} {r.p90_ms:8.2f} {per_robot:9.2f}"
        lines.append(f"{r.strategy:>14} {r.robots:>6} {r.threads!s:>7} {times} {split}")
    lines.append("(phase columns are per-step medians; they need not add up to the median;")
    lines.append(" with threads they add up the time spent on every thread; sensing holds the map")
    lines.append(" update of scans without range noise, cast and folded in one call)")
    peak = peak_resident_mb()
    if peak is not None:
        lines.append(f"peak resident memory of this process: {peak:.0f} MB")
    return "\n".join(lines)


def peak_resident_mb() -> float | None:
    """This process's peak resident memory in MB (None where the platform does not say)."""
    try:
        import resource
    except ImportError:  # not on Windows
        return None
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return peak / 2**20 if sys.platform == "darwin" else peak / 2**10  # bytes on macOS


def run_bench(
    robot_counts: Sequence[int],
    map_path: Path | None,
    warmup: int | None,
    measured: int | None,
    preset_name: str = "office",
    threads: Sequence[int | Literal["auto"]] = (1,),
    strategies: Sequence[str] = ("frontier",),
) -> str:
    """Time every team size with a preset (its map unless ``map_path``) and return the report."""
    preset = PRESETS[preset_name]
    path = map_path or preset.map_path
    if not path.is_file():
        raise MresimError(
            f"benchmark map {path} not found; give one with --map (an 800x600 floor plan whose"
            f" free space contains {list(preset.base)} and the starts from"
            f" {list(preset.start)})."
        )
    warm = preset.warmup if warmup is None else warmup
    steps = preset.steps if measured is None else measured
    results = [
        r
        for n in robot_counts
        for r in time_team(n, path, warm, steps, preset, threads, strategies)
    ]
    return report(results, path, preset)
