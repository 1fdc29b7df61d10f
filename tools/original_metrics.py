"""Runs of the original MRESim and of ours, read into milestones in one denominator.

The pure half of ``tools/compare_original.py`` (a script's module, not the package's):
the original's driver output (``cycle wall cpu gui joint base ...``) and ``--poslog``,
our run folders (``metrics.csv``, ``log/steps.jsonl``, ``summary.json`` and the tool's
``denominators.json``) become a :class:`Curve` of cells known per step, counted against
the original's ``totalArea`` (every non-obstacle pixel of its 800x600 grid), and one
:class:`Track` per robot; :func:`run_result` turns them into the steps to 50 / 90 / 95 %
explored and to 95 % at base (None: never), the final fractions and two diagnostics (the
distance to each newly picked target, the share of steps moving < 5 cells, exploring and
going home).
Our fractions are of E, our explorable cells: round(fraction * E) is the count, count / T
the original's fraction. :func:`censored_median` puts a never after every
reached value.
"""

from __future__ import annotations

import csv
import itertools
import json
import math
import statistics
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from PIL import Image

GRID = (600, 800)  # the original's rows, columns
THRESHOLDS = {"e50": 0.5, "e90": 0.9, "e95": 0.95}
BASE_THRESHOLD = 0.95
SLOW = 5.0  # cells moved in a step below which a robot counts as (nearly) standing
EXPLORING = ("active", "error")  # our robot states that still explore
INIT_CYCLES = 3  # the original's first cycles: a random walk, no frontier target
HOME_RADIUS = 10.0  # cells from the base within which a robot that is done is parked


class CompareError(Exception):
    """A mistake in the command line or a results file: printed, exit 2."""


@dataclass(frozen=True)
class Curve:
    """Cells known per step, in the original's denominator (``total``)."""

    steps: list[int]
    explored: list[int]
    base: list[int]
    total: int


@dataclass(frozen=True)
class Track:
    """One robot through a run: per step its position, goal, whether it explores, and
    the distance it moved in that step (index 0: the first recorded step); ``home`` is
    the base station's position."""

    positions: list[tuple[float, float]]
    goals: list[tuple[float, float] | None]
    exploring: list[bool]
    moved: list[float]
    home: tuple[float, float]


@dataclass(frozen=True)
class RunResult:
    """One run's milestones (None: never), final fractions and diagnostics."""

    milestones: dict[str, int | None]
    final_explored: float
    final_base: float
    steps: int
    goal_distance: float | None
    slow_exploring: float | None  # share of exploring robot-steps moving < SLOW
    slow_returning: float | None  # the same for steps going home (away from the base)
    wall_s: float | None


def original_obstacles(image: Path) -> NDArray[np.bool_]:
    """The original's wall pixels: first band == 0, a smaller image centred on free space."""
    with Image.open(image) as img:
        band = np.asarray(img)
    band = band if band.ndim == 2 else band[..., 0]
    rows, cols = band.shape
    if rows > GRID[0] or cols > GRID[1]:
        raise CompareError(f"{image} is {cols}x{rows}: the original refuses maps over 800x600")
    grid = np.zeros(GRID, dtype=bool)
    top, left = (GRID[0] - rows) // 2, (GRID[1] - cols) // 2
    grid[top : top + rows, left : left + cols] = band == 0
    return grid


def original_total_area(image: Path) -> int:
    """The original's ``totalArea``: every non-obstacle pixel of the 800x600 grid."""
    return int(np.count_nonzero(~original_obstacles(image)))


def to_original_cells(fraction: float, ours_total: int) -> int:
    """Our fraction of ``ours_total`` (explorable) cells, back to a count of cells."""
    return round(fraction * ours_total)


def first_reaching(curve: Curve, counts: Sequence[int], threshold: float) -> int | None:
    """The first step whose count is at least ``threshold`` of the curve's total."""
    for step, count in zip(curve.steps, counts, strict=True):
        if count >= threshold * curve.total:
            return step
    return None


def milestones(curve: Curve) -> dict[str, int | None]:
    """Steps to 50 / 90 / 95 % explored (e50, e90, e95) and to 95 % at base (b95)."""
    found = {key: first_reaching(curve, curve.explored, t) for key, t in THRESHOLDS.items()}
    found["b95"] = first_reaching(curve, curve.base, BASE_THRESHOLD)
    return found


def censored_median(values: Sequence[float | None]) -> float | None:
    """Median with never (None) later than everything; None when it is a never."""
    if not values:
        return None
    middle = float(np.median([math.inf if v is None else v for v in values]))
    return None if math.isinf(middle) else middle


def goal_pick_distances(track: Track) -> list[float]:
    """Straight-line distance from where a robot stood to each new target it picked while
    exploring (a step whose goal differs from the previous step's)."""
    found = []
    for i in range(1, len(track.goals)):
        goal = track.goals[i]
        if track.exploring[i] and goal is not None and goal != track.goals[i - 1]:
            x, y = track.positions[i - 1]
            found.append(math.hypot(goal[0] - x, goal[1] - y))
    return found


def slow_steps(track: Track, returning: bool = False, below: float = SLOW) -> tuple[int, int]:
    """(steps moving less than ``below``, steps) of one robot while exploring, or while
    going home (not exploring, and more than ``HOME_RADIUS`` from the base at the step's
    start: a robot parked at the base is not slow)."""
    moves = []
    for i in range(1, len(track.moved)):
        away = math.dist(track.positions[i - 1], track.home) > HOME_RADIUS
        if (not track.exploring[i] and away) if returning else track.exploring[i]:
            moves.append(track.moved[i])
    return sum(m < below for m in moves), len(moves)


def slow_share(tracks: Sequence[Track], returning: bool) -> float | None:
    """The share of the team's robot-steps of one kind that moved less than ``SLOW``."""
    counts = [slow_steps(track, returning) for track in tracks]
    steps = sum(n for _, n in counts)
    return sum(k for k, _ in counts) / steps if steps else None


def over_explorable(curve: Curve, explorable: int) -> Curve:
    """The original's curve as fractions of our explorable cells (counts capped there:
    a pixel the original saw that no body of ours can see counts once the rest is seen)."""
    explored = [min(n, explorable) for n in curve.explored]
    base = [min(n, explorable) for n in curve.base]
    return Curve(curve.steps, explored, base, explorable)


def run_result(curve: Curve, tracks: Sequence[Track], wall_s: float | None) -> RunResult:
    """Milestones, finals and diagnostics of one run."""
    picks = [d for track in tracks for d in goal_pick_distances(track)]
    return RunResult(
        milestones(curve),
        curve.explored[-1] / curve.total,
        curve.base[-1] / curve.total,
        curve.steps[-1],
        statistics.median(picks) if picks else None,
        slow_share(tracks, returning=False),
        slow_share(tracks, returning=True),
        wall_s,
    )


def read_original_output(path: Path) -> tuple[Curve, float | None]:
    """The driver's per-cycle table (``cycle wall cpu gui joint base ...``) as a curve, and
    the run's wall time if the file records it (``# wall_s=``)."""
    total, wall, rows = None, None, []
    for line in read_text(path).splitlines():
        if line.startswith("#"):
            for word in line.split():
                if word.startswith("totalFree="):
                    total = int(word.split("=")[1])
                if word.startswith("wall_s="):
                    wall = float(word.split("=")[1])
            continue
        fields = line.split()
        if len(fields) == 8 and fields[0].isdigit():
            rows.append((int(fields[0]), int(fields[4]), int(fields[5])))
    if total is None or not rows:
        raise CompareError(
            f"{path}: not an output of the original's driver (no totalFree= or rows)"
        )
    steps, joint, base = (list(column) for column in zip(*rows, strict=True))
    return Curve(steps, joint, base, total), wall


def read_poslog(path: Path, home: tuple[float, float]) -> list[Track]:
    """The driver's ``--poslog`` (``cycle robot x y heading goal_x goal_y state``) as one
    track per robot; a robot explores unless in its first ``INIT_CYCLES`` (a random walk)
    or going home (its goal is the base's pixel ``home``: the original's mission complete).
    The state column does not tell: frontier exploration leaves every robot ``Initial``."""
    rows: dict[str, list[list[str]]] = {}
    for line in read_text(path).splitlines()[1:]:
        fields = line.split()
        if len(fields) == 8:
            rows.setdefault(fields[1], []).append(fields)
    tracks = []
    for robot_rows in rows.values():
        positions = [(float(r[2]), float(r[3])) for r in robot_rows]
        goals = [None if r[5] == "-1" else (float(r[5]), float(r[6])) for r in robot_rows]
        exploring = [
            int(r[0]) > INIT_CYCLES and g != home for r, g in zip(robot_rows, goals, strict=True)
        ]
        moved = [0.0] + [math.dist(a, b) for a, b in itertools.pairwise(positions)]
        tracks.append(Track(positions, goals, exploring, moved, home))
    return tracks


def base_pixel(team: Path) -> tuple[float, float]:
    """The base station's pixel, from the team file's first line."""
    fields = read_text(team).split()
    return float(fields[2]), float(fields[3])


def read_text(path: Path) -> str:
    """A results or team file's text; CompareError naming it if it cannot be read."""
    try:
        return path.read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise CompareError(f"{path}: cannot read ({exc.strerror or exc})") from None


def read_json(path: Path) -> dict[str, Any]:
    """A JSON object from a results file; CompareError naming it if it is none."""
    try:
        data = json.loads(read_text(path))
    except json.JSONDecodeError as exc:
        raise CompareError(f"{path}: not JSON ({exc})") from None
    if not isinstance(data, dict):
        raise CompareError(f"{path}: not a JSON object")
    return data


def read_ours(run_dir: Path, explorable: bool = False) -> RunResult:
    """One of our runs: metrics.csv, log/steps.jsonl, denominators.json, summary.json;
    fractions of the original's free pixels, or of our explorable cells (``explorable``)."""
    try:
        return read_ours_files(run_dir, explorable)
    except (KeyError, ValueError, IndexError, TypeError) as exc:
        raise CompareError(f"{run_dir}: not a complete run of this tool ({exc!r})") from None


def read_ours_files(run_dir: Path, explorable: bool = False) -> RunResult:
    """:func:`read_ours` without the error wrapping."""
    counts = read_json(run_dir / "denominators.json")
    ours, total = int(counts["ours_explorable_cells"]), int(counts["original_total_area"])
    total = ours if explorable else total
    with open(run_dir / "metrics.csv", newline="", encoding="utf-8") as handle:
        rows = list(csv.DictReader(handle))
    curve = Curve(
        [int(r["step"]) for r in rows],
        [to_original_cells(float(r["explored"]), ours) for r in rows],
        [to_original_cells(float(r["known_at_base"]), ours) for r in rows],
        total,
    )
    names = [c.removeprefix("state_") for c in rows[0] if c.startswith("state_")]
    lines = [json.loads(x) for x in read_text(run_dir / "log" / "steps.jsonl").splitlines()]
    tracks = []
    base = lines[0]["agents"][0]["position"]
    for i, name in enumerate(names, 1):
        agents = [line["agents"][i] for line in lines[: len(rows)]]
        tracks.append(
            Track(
                [(a["position"][0], a["position"][1]) for a in agents],
                [None if a["goal"] is None else (a["goal"][0], a["goal"][1]) for a in agents],
                [r[f"state_{name}"] in EXPLORING for r in rows],
                [float(r[f"distance_{name}"]) for r in rows],
                (base[0], base[1]),
            )
        )
    wall = read_json(run_dir / "summary.json").get("wall_time_s")
    return run_result(curve, tracks, None if wall is None else float(wall))
