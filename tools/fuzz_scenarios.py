"""Fuzz the scenario input: malformed scenario files, each run through ``mresim run``.

Every file must either run (exit 0, its 3 steps written) or be rejected with a
one-paragraph message naming the file (exit 2); anything else, an exception, a
warning (``inf`` or ``nan`` reaching the numbers), another exit code, is a crash.
The files are valid base scenarios on a small map (``maps/small_rooms.png``, copied
into a work folder) mutated by hypothesis: wrong types, non-finite, huge and
boolean numbers, unknown and missing keys, deleted sections, random strings,
bad plugin references, and on the YAML text itself duplicated keys, deep
nesting, stray characters and cut-off files.

    python tools/fuzz_scenarios.py [--count 1000] [--seed 0] [--show 5]

prints the counts (accepted, rejected with a message, crashes) and the first
crashes. ``tests/test_fuzz.py`` runs a few hundred of the same files in the suite.
"""

from __future__ import annotations

import argparse
import contextlib
import copy
import io
import json
import math
import os
import shutil
import sys
import tempfile
import traceback
import warnings
from collections import Counter
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import seed as hypothesis_seed
from hypothesis import strategies as st

ROOT = Path(__file__).resolve().parent.parent
MAP = ROOT / "maps" / "small_rooms.png"  # 160x120, four rooms and a hall
STEPS = 3

# --- valid starting points --------------------------------------------------------------

PLAIN: dict[str, Any] = {
    "name": "fuzz",
    "seed": 1,
    "steps": 40,
    "stop": {"explored": 0.99},
    "map": {"image": "small_rooms.png", "resolution": 0.1},
    "base_station": {"position": [20, 60], "comm_range": 40},
    "team": {
        "speed": 3,
        "radius": 2,
        "sensor": {"range": 60, "fov_deg": 180, "rays": 31},
        "comm_range": 40,
        "strategy": "frontier",
    },
    "robots": [
        {"name": "A", "start": [66, 52], "heading_deg": 0},
        {"name": "B", "start": [66, 68], "heading_deg": 180, "speed": 4},
    ],
    "communication": {"model": "disk"},
}


def with_changes(**changes: Any) -> dict[str, Any]:
    """:data:`PLAIN` with top-level keys replaced."""
    return {**copy.deepcopy(PLAIN), **changes}


BASES: list[dict[str, Any]] = [
    PLAIN,
    with_changes(
        communication={
            "model": "path_loss",
            "params": {"reference_dbm": -93, "exponent": 2.5, "wall_db": 3.65, "cutoff_dbm": -93},
            "dropout": 0.1,
            "control": {"model": "disk", "range": 200, "dropout": 0.0},
        },
        base_station={"position": [20, 60], "comm_range": 40, "comm_power_dbm": -80},
    ),
    with_changes(
        team={
            "speed": 2.5,
            "radius": 1.5,
            "sensor": {"range": 40, "rays": 21, "noise_std": 0.5, "safe_fraction": 0.2},
            "comm_range": 30,
            "wall_margin": 1.0,
            "strategy": {"name": "random_walk", "params": {"replan_interval": 5, "distance": 20}},
            "planner": {"name": "topological", "params": {"node_spacing": 10, "smooth": True}},
        },
        communication={"model": "line_of_sight", "params": {"clearance": 0.5}},
    ),
    with_changes(
        events=[
            {"step": 0, "fail": "B"},
            {"step": 1, "until": 3, "blackout": ["A", "base"], "channel": "main"},
            {"step": 2, "cells": [100, 10, 104, 20]},
        ],
        render={"snapshots": [0, 2], "final_png": True, "layers": "default", "scale": 1.0},
        simulation={
            "scan": "step",
            "robots_block": True,
            "presume_lost_after": 50,
            "start_jitter": {"position": 2.0, "heading_deg": 10.0},
        },
    ),
    with_changes(
        team={
            **copy.deepcopy(PLAIN["team"]),
            "strategy": {
                "name": "frontier",
                "params": {"replan_interval": 10, "horizon": 1.5, "give_up_radius": 8.0},
            },
        },
        stop={"explored": 0.9, "known_at_base": 0.8, "all_done": True},
    ),
]

# --- values and mutations -----------------------------------------------------------------

SPECIAL: list[Any] = [
    *(math.inf, -math.inf, math.nan, 1e308, -1e308, 1e30, 1e20, 1e7, 100_001.0, 1e-300),
    *(0, 0.0, -0.0, -1, -1.5, 1, 0.5, 2**31, 2**63, 2**64, 10**30, -(10**30)),
    *(True, False, None),
    *("", ".", "..", ":", "a:", ":b", "os:path", "..x:Y", "mresim_phys.cli:main", "x.y:Z"),
    *("frontier", "random_walk", "path_loss", "topological", "nope", "base", "A", "B"),
    *("1e30", ".inf", "nan", "true", "3", "small_rooms.png", "missing.png"),
    *([], {}, [1, 2], [1, 2, 3], [[1, 2]], [True, 2], {"a": 1}, {"name": "x"}, [{}]),
]
KEYS = ["speed", "range", "name", "params", "fail", "step", "seed", "x", "Speed", "rays_"]
TEXT = st.text(st.characters(blacklist_characters="/\\", codec="utf-8"), max_size=12)
LEAVES: st.SearchStrategy[Any] = st.one_of(
    st.sampled_from(SPECIAL),
    st.integers(-(10**12), 10**12),
    st.floats(),
    st.booleans(),
    TEXT,
)
VALUES: st.SearchStrategy[Any] = st.one_of(
    LEAVES,
    st.lists(LEAVES, max_size=4),
    st.dictionaries(st.sampled_from(KEYS), LEAVES, max_size=3),
)
SCALES = [1e3, 1e6, 1e30, 1e300, -1.0, 0.0, 1e-30, -1e6]
EDGES = [0, 1e-9, 1e-3, 0.01, 1, 2, 64, 999, 1000, 4096, 1e5, 1e6, -1e6, 10**9, -300, 300]
Path_ = tuple[Any, ...]  # keys and list indices from the top of a scenario


def paths(data: Any, prefix: Path_ = ()) -> Iterator[Path_]:
    """Every key path in ``data``, parents before children."""
    items = data.items() if isinstance(data, dict) else enumerate(data)
    for key, value in items:
        yield (*prefix, key)
        if isinstance(value, (dict, list)):
            yield from paths(value, (*prefix, key))


def parent_of(data: Any, path: Path_) -> Any:
    """The container holding the last key of ``path``."""
    for key in path[:-1]:
        data = data[key]
    return data


def mutate(draw: Callable[..., Any], data: dict[str, Any]) -> None:
    """One random change to ``data`` at a random path (in place)."""
    path = draw(st.sampled_from(list(paths(data))))
    parent, key = parent_of(data, path), path[-1]
    ops = ["set", "set", "delete", "unknown", "scale", "section", "edge", "edge", "edge", "late"]
    op = draw(st.sampled_from(ops))
    if op == "set":
        parent[key] = draw(VALUES)
    elif op == "delete":
        del parent[key]
    elif op == "unknown" and isinstance(parent, dict):
        parent[draw(st.one_of(st.sampled_from(KEYS), TEXT))] = draw(LEAVES)
    elif op == "scale" and isinstance(parent[key], (int, float)):
        parent[key] = parent[key] * draw(st.sampled_from(SCALES))
    elif op == "edge" and isinstance(parent[key], (int, float)):  # often valid, yet extreme
        parent[key] = draw(st.sampled_from(EDGES))
    elif op == "late":  # an event after the step cap, or a door under a cell long
        if draw(st.booleans()):
            steps = data.get("steps")
            cap = steps if isinstance(steps, int) and not isinstance(steps, bool) else 40
            data["events"] = [{"step": cap + 1, "fail": "A"}]
        else:
            data["doors"] = [{"name": "d", "between": [[30, 30], [30, 30.5]]}]
    elif op == "section":
        data[draw(st.sampled_from(list(data)))] = draw(LEAVES)


def mutate_text(draw: Callable[..., Any], text: str) -> str:
    """One random change to the YAML text: a duplicated line, deep nesting, noise, a cut."""
    lines = text.splitlines()
    ops = ["duplicate", "duplicate", "nest", "noise", "cut", "tab", "bomb", "loop", "binary"]
    op = draw(st.sampled_from(ops))
    at = draw(st.integers(0, max(len(lines) - 1, 0)))
    if op == "duplicate":  # a key line given twice (at any depth) or a list item repeated
        lines.insert(at, lines[at])
    elif op == "nest":
        depth = draw(st.sampled_from([10, 100, 400, 5000]))
        lines.append("deep: " + "[" * depth + "]" * depth)
    elif op == "noise":
        place = draw(st.integers(0, len(text)))
        char = draw(st.sampled_from(list(":{}[]&*!|>'\"%@`#\t-?,\x00\ufeff")))
        return text[:place] + char + text[place:]
    elif op == "cut":
        return text[: draw(st.integers(0, len(text)))]
    elif op == "bomb":  # a billion laughs: 10^levels values through aliases
        levels = draw(st.integers(2, 9))
        lines += ["l0: &l0 [{name: a, start: [1, 1]}]"]
        lines += [f"l{i}: &l{i} [" + ", ".join([f"*l{i - 1}"] * 10) + "]" for i in range(1, levels)]
        key = draw(st.sampled_from(["robots", "events", "bomb", "doors"]))
        lines = [line for line in lines if not line.startswith(f"{key}:")] + [
            f"{key}: *l{levels - 1}"
        ]
    elif op == "loop":  # an alias inside its own value
        lines.append(draw(st.sampled_from(["loop: &a [1, *a]", "loop: &a {k: *a}"])))
    elif op == "binary":  # a !!binary value where text or a number belongs
        key = draw(st.sampled_from(["name", "seed", "steps"]))
        lines = [
            f"{key}: !!binary aGVsbG8=" if line.startswith(f"{key}:") else line for line in lines
        ]
    else:
        lines[at] = "\t" + lines[at]
    return "\n".join(lines) + "\n"


@st.composite
def scenario_texts(draw: Callable[..., Any]) -> str:
    """A scenario file's text: a base scenario, a few changes, sometimes a text change."""
    data = copy.deepcopy(draw(st.sampled_from(BASES)))
    for _ in range(draw(st.integers(1, 3))):
        mutate(draw, data)
    text = yaml.safe_dump(data, sort_keys=False, allow_unicode=True)
    if draw(st.integers(0, 3)) == 0:
        text = mutate_text(draw, text)
    return text


# --- running one file -----------------------------------------------------------------------


@dataclass
class Outcome:
    """What ``mresim run`` made of one file: 'accepted', 'rejected' or 'crash', and why."""

    kind: str
    detail: str = ""


@contextlib.contextmanager
def inside(folder: Path) -> Iterator[None]:
    """Run with ``folder`` as the current folder (videos and runs land there)."""
    previous = Path.cwd()
    os.chdir(folder)
    try:
        yield
    finally:
        os.chdir(previous)


def prepare(folder: Path) -> Path:
    """A work folder holding the map every base scenario names."""
    folder.mkdir(parents=True, exist_ok=True)
    shutil.copy(MAP, folder / MAP.name)
    return folder


def run_file(path: Path, out_dir: Path) -> Outcome:
    """Run ``path`` for :data:`STEPS` steps through the CLI entry point and judge the result."""
    from mresim_phys.cli import main

    err = io.StringIO()
    args = ["run", str(path), "--steps", str(STEPS), "--quiet", "--no-plots", "--out", str(out_dir)]
    try:
        with contextlib.redirect_stderr(err), warnings.catch_warnings():
            warnings.simplefilter("error")  # a RuntimeWarning means inf/nan reached the run
            code = main(args)
    except BaseException:  # anything escaping the CLI is what we look for
        return Outcome("crash", traceback.format_exc())
    if code == 2:
        return judge_message(path, err.getvalue())
    if code != 0:
        return Outcome("crash", f"exit {code}: {err.getvalue()}")
    return judge_run(out_dir)


def judge_message(path: Path, message: str) -> Outcome:
    """A rejection must be one message naming the file (or the map file beside it)."""
    if not message.startswith("mresim: error: ") or "Traceback" in message:
        return Outcome("crash", f"exit 2 without a proper message: {message!r}")
    if str(path.parent) not in message and path.name not in message:
        return Outcome("crash", f"exit 2, message does not name the file: {message!r}")
    return Outcome("rejected", message)


def judge_run(out_dir: Path) -> Outcome:
    """An accepted file ran: its summary, metrics (one row per step) and scenario written."""
    from mresim_phys.scenario.load import validate_scenario
    from mresim_phys.scenario.readers import read_yaml_mapping

    summary = json.loads((out_dir / "summary.json").read_text(encoding="utf-8"))
    rows = (out_dir / "metrics.csv").read_text(encoding="utf-8").strip().splitlines()
    steps = summary["steps"]
    if not (steps == STEPS or (steps < STEPS and summary["stop_reason"] != "steps")):
        return Outcome("crash", f"ran {steps} steps, not {STEPS}: {summary['stop_reason']}")
    if len(rows) != steps + 2:  # header and step 0
        return Outcome("crash", f"metrics.csv has {len(rows)} lines for {steps} steps")
    resolved = out_dir / "scenario.yaml"
    validate_scenario(read_yaml_mapping(resolved), str(resolved))  # the run's record re-reads
    return Outcome("accepted")


def check_text(text: str, folder: Path, number: int) -> Outcome:
    """Write ``text`` as scenario ``number`` in ``folder`` and run it (its outputs removed)."""
    path = folder / f"case-{number:05d}.yaml"
    path.write_text(text, encoding="utf-8")
    out_dir = folder / f"out-{number:05d}"
    try:
        with inside(folder):
            return run_file(path, out_dir)
    except Exception:  # a broken run folder is a crash too
        return Outcome("crash", traceback.format_exc())
    finally:
        shutil.rmtree(out_dir, ignore_errors=True)
        shutil.rmtree(folder / "videos", ignore_errors=True)


# --- many files -----------------------------------------------------------------------------


@dataclass
class Tally:
    """Counts of outcomes and the crashes seen, with their files' text."""

    counts: Counter[str] = field(default_factory=Counter)
    crashes: list[tuple[str, str]] = field(default_factory=list)

    def add(self, text: str, outcome: Outcome) -> None:
        self.counts[outcome.kind] += 1
        if outcome.kind == "crash":
            self.crashes.append((text, outcome.detail))


def fuzz(count: int, folder: Path, seed: int | None = 0) -> Tally:
    """Run ``count`` generated files (reproducible for a given ``seed``)."""
    prepare(folder)
    tally = Tally()

    def one(text: str) -> None:
        tally.add(text, check_text(text, folder, sum(tally.counts.values())))

    run_cases(count, seed, scenario_texts(), one)
    return tally


def run_cases(
    count: int, seed: int | None, cases: st.SearchStrategy[Any], check: Callable[[Any], None]
) -> None:
    """``check`` each of ``count`` cases drawn from ``cases``: reproducible for a given
    ``seed``, derandomized (the suite's fixed cases) when ``seed`` is None. The study and
    viewer fuzzers draw through this too."""

    @settings(
        max_examples=count,
        deadline=None,
        database=None,
        derandomize=seed is None,
        suppress_health_check=list(HealthCheck),
    )
    @given(cases)
    def one(case: Any) -> None:
        check(case)

    (hypothesis_seed(seed)(one) if seed is not None else one)()


def main(argv: list[str] | None = None) -> int:
    """Print the counts of ``--count`` fuzzed files; exit 1 if any crashed."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=1000, help="files to generate (1000)")
    parser.add_argument("--seed", type=int, default=0, help="hypothesis seed (0)")
    parser.add_argument("--show", type=int, default=5, help="crashes to print in full (5)")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="mresim-fuzz-") as work:
        tally = fuzz(args.count, Path(work), args.seed)
    counts = tally.counts
    print(
        f"{sum(counts.values())} files: {counts['accepted']} accepted (ran {STEPS} steps),"
        f" {counts['rejected']} rejected with a message, {counts['crash']} crashes"
    )
    for text, detail in tally.crashes[: args.show]:
        print("-" * 72, "\n" + text, "\n" + detail, file=sys.stderr)
    return 1 if counts["crash"] else 0


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))
    sys.exit(main())
