"""Fuzz the study input: malformed study files, each read and expanded as ``mresim sweep`` does.

Every file must either be accepted (read, every arm checked, and its first runs of a few
steps run by the sweep's own worker without failing) or be rejected with a one-paragraph
message naming the file (what ``mresim sweep`` prints with exit 2); anything else, an
exception, a warning, a failed run of an accepted file, or a file that takes more than
``--limit`` seconds, is a crash. The files are valid studies of small scenarios on a small
map (``maps/small_rooms.png``, copied into a work folder) mutated by hypothesis: the
scenario fuzzer's changes (``tools/fuzz_scenarios.py``: wrong types, non-finite, huge
and boolean numbers, unknown and missing keys, deleted sections) and the study's own
(names leaving the sweeps folder, a billion seeds, huge grids, booleans and quoted
numbers, values given twice, plugin references of the wrong family or none, missing
scenario files, YAML alias bombs), and on the YAML text duplicated keys, deep nesting,
stray characters and cut-off files. Each file is checked in a child process, killed and
restarted when a file takes too long, so a hang is counted, not waited for.

    python tools/fuzz_studies.py [--count 1000] [--seed 0] [--show 5] [--limit 10]

prints the counts (accepted, rejected with a message, crashes) and the first crashes.
``tests/test_fuzz_studies.py`` runs a few hundred of the same files in the suite.
"""

from __future__ import annotations

import argparse
import contextlib
import copy
import dataclasses
import multiprocessing
import shutil
import sys
import tempfile
import traceback
import warnings
from collections.abc import Callable
from multiprocessing.connection import Connection
from pathlib import Path
from typing import Any

import yaml
from hypothesis import strategies as st

TOOLS = Path(__file__).resolve().parent
sys.path[:0] = [str(TOOLS), str(TOOLS.parent)]  # the scenario fuzzer; the package (children)

import fuzz_scenarios as scenarios  # noqa: E402
from fuzz_scenarios import Outcome, Tally, inside  # noqa: E402

STEPS = 3  # steps of each run of an accepted file
RUNS = 2  # runs of an accepted file that are run
LIMIT = 10.0  # seconds a file may take

# --- valid starting points --------------------------------------------------------------

SCENARIOS = {  # base scenarios written into the work folder
    "base.yaml": scenarios.PLAIN,
    "sight.yaml": scenarios.BASES[2],
    "events.yaml": scenarios.BASES[3],
}
BASES: list[dict[str, Any]] = [
    {
        "name": "fz",
        "scenarios": ["base.yaml"],
        "axes": {"team.strategy": ["frontier", "random_walk"]},
        "seeds": 2,
        "steps": 20,
    },
    {
        "name": "fz-failures",
        "scenarios": ["base.yaml", "sight.yaml"],
        "axes": {"team": {"comm_range": [20, 40]}, "failures": [0, 1]},
        "seeds": [0, 3],
        "steps": 40,
        "failure_window": [0.1, 0.5],
        "reference": {"team.comm_range": 20, "failures": 0},
    },
    {
        "name": "fz.zip",
        "scenarios": ["base.yaml"],
        "axes": {"team.speed": [2, 3], "robots.count": [1, 3]},
        "mode": "zip",
        "seeds": 1,
        "overrides": {"stop.explored": 0.9, "team.sensor.rays": 21},
    },
    {
        "name": "fz_faults",
        "scenarios": ["events.yaml"],
        "axes": {
            "faults.random.mtbf": [50, None],
            "communication.model": ["disk", "line_of_sight"],
            "team.planner": ["astar", "jps"],
        },
        "seeds": 1,
        "steps": 10,
    },
]

# --- values and mutations -----------------------------------------------------------------

NAMES = ["../../escaped", "/tmp/escaped", "a/b", "..", ".", "", "~", "a" * 65, "ok-name"]
PLUGINS = [
    "mresim_phys.comms.disk:DiskComm",
    "mresim_phys.planning.astar:AStar",
    "mresim_phys.strategies.frontier:FrontierExploration",
    "mresim_phys.world.events:Failure",
    "mresim_phys.world.space:World",
    "mresim_phys.strategies.random_walk:RandomWalk",
    "no_such_pkg:X",
    "os:path",
    ":",
]
PLUGIN_FIELDS = ["team.strategy", "team.planner", "communication.model", "robots.A.strategy"]
NUMBERS: list[Any] = [True, False, "20", "1e3", "0x10", 2.5, -1, 0, 10**9, 10**12, [True], ["1"]]
NUMBER_FIELDS = ["seeds", "steps", "failure_window", "failures"]
FILES = ["missing.yaml", "small_rooms.png", "../base.yaml", ".", "base.yaml", "/dev/null"]
VALID: list[tuple[str, Any]] = [  # changes that keep a study valid, to reach what follows
    ("seeds", 1),
    ("seeds", [5]),
    ("seeds", [0, 7]),
    ("steps", 1),
    ("steps", None),
    ("failure_window", [0, 1]),
    ("failure_window", [0.2, 0.3]),
    ("axes.team.comm_range", [10, 30]),
    ("axes.team.sensor.range", [20, 40]),
    ("axes.communication.model", ["path_loss"]),
    ("axes.robots.count", [1, 2]),
    ("axes.failures", [0, 2]),
    ("axes.faults.random.mtbf", [80]),
    ("axes.team.strategy", ["mresim_phys.strategies.random_walk:RandomWalk"]),
    ("overrides.stop.explored", 0.5),
    ("overrides.team.planner", "topological"),
]


def study_mutate(draw: Callable[..., Any], data: dict[str, Any]) -> None:
    """One change only a study has (in place)."""
    data.setdefault("axes", {})
    axes = data["axes"] if isinstance(data["axes"], dict) else {}
    ops = ["name", "plugin", "number", "huge", "twice", "file", "axis", "valid", "valid"]
    op = draw(st.sampled_from(ops))
    if op == "valid":
        valid(draw, data, axes)
    elif op == "name":
        data["name"] = draw(st.sampled_from(NAMES))
    elif op == "plugin":
        plugin(draw, data, axes)
    elif op == "number":
        number_field(draw, data, axes)
    elif op == "huge":
        huge(draw, data, axes)
    elif op == "twice":
        twice(draw, data, axes)
    elif op == "file":
        given = data.get("scenarios")
        data["scenarios"] = [
            *(given if isinstance(given, list) else []),
            draw(st.sampled_from(FILES)),
        ]
    else:
        axes[draw(st.sampled_from(["team.speed", "nope.field", "failures", "robots.count"]))] = (
            draw(scenarios.VALUES)
        )


def valid(draw: Callable[..., Any], data: dict[str, Any], axes: dict[str, Any]) -> None:
    """A change that keeps the study valid (most of the time: a zip study may need more)."""
    field, value = draw(st.sampled_from(VALID))
    section, _, rest = field.partition(".")
    if section == "axes":
        axes[rest] = copy.deepcopy(value)
    elif section == "overrides" and isinstance(data.get("overrides", {}), dict):
        data.setdefault("overrides", {})[rest] = value
    elif value is None:
        data.pop(field, None)
    else:
        data[field] = copy.deepcopy(value)


def plugin(draw: Callable[..., Any], data: dict[str, Any], axes: dict[str, Any]) -> None:
    """A plugin reference (of the wrong family, or none) in an axis or an override."""
    field, value = draw(st.sampled_from(PLUGIN_FIELDS)), draw(st.sampled_from(PLUGINS))
    overrides = data.get("overrides")
    if draw(st.booleans()) and isinstance(overrides, dict):
        overrides[field] = value
    else:
        axes[field] = ["random_walk" if "planner" not in field else "astar", value]


def number_field(draw: Callable[..., Any], data: dict[str, Any], axes: dict[str, Any]) -> None:
    """A boolean, a quoted number or an odd number where the study takes a number."""
    field, value = draw(st.sampled_from(NUMBER_FIELDS)), draw(st.sampled_from(NUMBERS))
    if field == "failures":
        axes["failures"] = value if isinstance(value, list) else [value]
    elif field == "failure_window":
        data[field] = [value, 0.5]
    else:
        data[field] = value


def huge(draw: Callable[..., Any], data: dict[str, Any], axes: dict[str, Any]) -> None:
    """A study of very many runs: a billion seeds, or a grid of long axes."""
    if draw(st.booleans()):
        data["seeds"] = draw(st.sampled_from([10**5, 10**5 + 1, 10**9]))
    else:
        width = draw(st.sampled_from([10, 50, 400]))
        for i in range(draw(st.integers(2, 6))):
            axes[f"team.sensor.p{i}"] = list(range(width))


def twice(draw: Callable[..., Any], data: dict[str, Any], axes: dict[str, Any]) -> None:
    """A value given twice: an axis value, a seed, a scenario."""
    lists = [v for v in axes.values() if isinstance(v, list) and v]
    for holder in ("seeds", "scenarios"):
        if isinstance(data.get(holder), list) and data[holder]:
            lists.append(data[holder])
    if lists:
        chosen = draw(st.sampled_from(lists))
        chosen.append(copy.deepcopy(draw(st.sampled_from(chosen))))


def alias_bomb(draw: Callable[..., Any], data: dict[str, Any]) -> None:
    """A billion laughs: nested lists sharing their items, written with YAML aliases."""
    bomb: Any = ["lol"] * 10
    for _ in range(draw(st.integers(4, 9))):
        bomb = [bomb] * 10
    place = draw(st.sampled_from(["axes", "overrides", "reference", "seeds", "scenarios"]))
    if place in ("axes", "overrides", "reference"):
        data[place] = {"team.speed": bomb}
    else:
        data[place] = bomb


@st.composite
def study_texts(draw: Callable[..., Any]) -> str:
    """A study file's text: a base study, a few changes, sometimes a text change."""
    data: dict[str, Any] = draw(st.sampled_from(BASES))
    for _ in range(draw(st.integers(1, 3))):
        data = copy.deepcopy(data)  # never change a base or a value the lists hold
        if draw(st.integers(0, 2)):
            study_mutate(draw, data)
        elif data:
            scenarios.mutate(draw, data)
    if draw(st.integers(0, 15)) == 0:
        alias_bomb(draw, data)  # last: the other changes would walk the whole bomb
    text = yaml.safe_dump(data, sort_keys=False, allow_unicode=True)
    if draw(st.integers(0, 3)) == 0:
        text = scenarios.mutate_text(draw, text)
    return text


# --- checking one file (in the child process) ---------------------------------------------


def prepare(folder: Path) -> Path:
    """A work folder holding the map and the base scenarios every base study names."""
    scenarios.prepare(folder)
    for name, data in SCENARIOS.items():
        (folder / name).write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return folder


def check_file(path: Path, sweep: Path) -> Outcome:
    """Read and expand ``path`` as ``mresim sweep`` does, then run its first runs."""
    from mresim_phys.errors import MresimError
    from mresim_phys.sweeps.expand import expand_runs
    from mresim_phys.sweeps.study import load_study

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            runs = expand_runs(load_study(path), path)
    except MresimError as exc:  # what the CLI prints, exit 2
        return scenarios.judge_message(path, f"mresim: error: {exc}")
    except OSError as exc:  # the CLI's 'cannot use FILE' message, exit 2
        return scenarios.judge_message(path, f"mresim: error: cannot use {exc.filename}")
    except BaseException:
        return Outcome("crash", traceback.format_exc())
    return run_first(runs, sweep)


def run_first(runs: list[Any], sweep: Path) -> Outcome:
    """The first :data:`RUNS` runs, :data:`STEPS` steps each, by the sweep's worker."""
    from mresim_phys.sweeps.worker import DONE, run_task

    for spec in runs[:RUNS]:
        short = dataclasses.replace(spec, data={**spec.data, "steps": STEPS})
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            record = run_task(short, str(sweep))
        if record["status"] != DONE:
            log = Path(record["log"]).read_text(encoding="utf-8")
            return Outcome("crash", f"run {spec.run_id} of an accepted file failed:\n{log}")
    return Outcome("accepted")


def check_text(text: str, folder: Path, number: int) -> Outcome:
    """Write ``text`` as study ``number`` in ``folder`` and check it (its outputs removed)."""
    path = folder / f"study-{number:05d}.yaml"
    path.write_text(text, encoding="utf-8")
    sweep = folder / f"sweep-{number:05d}"
    try:
        with inside(folder):
            return check_file(path, sweep)
    except BaseException:
        return Outcome("crash", traceback.format_exc())
    finally:
        shutil.rmtree(sweep, ignore_errors=True)
        path.unlink()


def serve(conn: Connection, folder: str) -> None:
    """The child's loop: first every base study (imports and compiles what a run needs;
    ("ready", "") once they pass), then (text, number) in, (kind, detail) out, until None."""
    for number, base in enumerate(BASES):
        outcome = check_text(yaml.safe_dump(base, sort_keys=False), Path(folder), 90_000 + number)
        if outcome.kind != "accepted":
            conn.send(("error", f"base study {number} is not accepted: {outcome.detail}"))
            return
    conn.send(("ready", ""))
    while (message := conn.recv()) is not None:
        outcome = check_text(message[0], Path(folder), message[1])
        conn.send((outcome.kind, outcome.detail))


# --- the parent: a child process per file, restarted when one takes too long -------------


class Checker:
    """Checks files in a child process; a file taking over ``limit`` seconds is a crash."""

    def __init__(self, folder: Path, limit: float = LIMIT) -> None:
        self.folder, self.limit = folder, limit
        self.context = multiprocessing.get_context("spawn")
        self.start()

    def start(self) -> None:
        """A new child, once it has checked the base studies (not timed)."""
        self.conn, child = self.context.Pipe()
        self.process = self.context.Process(target=serve, args=(child, str(self.folder)))
        self.process.start()
        child.close()
        try:
            kind, detail = self.conn.recv() if self.conn.poll(600) else ("error", "no answer")
        except (EOFError, OSError) as exc:
            kind, detail = "error", f"it died ({exc!r}, exit {self.process.exitcode})"
        if kind != "ready":
            self.close(kill=True)
            raise RuntimeError(f"the checking process did not start: {detail}")

    def check(self, text: str, number: int, limit: float | None = None) -> Outcome:
        """The outcome of one file; the child is restarted if it hangs or dies."""
        seconds = self.limit if limit is None else limit
        try:
            self.conn.send((text, number))
            if self.conn.poll(seconds):
                kind, detail = self.conn.recv()
                return Outcome(kind, detail)
            problem = f"took more than {seconds:g} s"
        except (EOFError, OSError) as exc:  # the child died (memory, a signal)
            problem = f"the checking process died ({exc!r}, exit {self.process.exitcode})"
        self.close(kill=True)
        self.start()
        return Outcome("crash", problem)

    def close(self, kill: bool = False) -> None:
        if kill:
            self.process.kill()
        else:
            with contextlib.suppress(OSError):
                self.conn.send(None)
        self.process.join()
        self.conn.close()


def fuzz(count: int, folder: Path, seed: int | None = 0, limit: float = LIMIT) -> Tally:
    """Check ``count`` generated files (reproducible for a given ``seed``)."""
    prepare(folder)
    tally = Tally()
    checker = Checker(folder, limit)
    try:
        scenarios.run_cases(
            count,
            seed,
            study_texts(),
            lambda text: tally.add(text, checker.check(text, sum(tally.counts.values()))),
        )
    finally:
        checker.close()
    return tally


def main(argv: list[str] | None = None) -> int:
    """Print the counts of ``--count`` fuzzed files; exit 1 if any crashed."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=1000, help="files to generate (1000)")
    parser.add_argument("--seed", type=int, default=0, help="hypothesis seed (0)")
    parser.add_argument("--show", type=int, default=5, help="crashes to print in full (5)")
    parser.add_argument("--limit", type=float, default=LIMIT, help="seconds a file may take")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="mresim-fuzz-studies-") as work:
        tally = fuzz(args.count, Path(work), args.seed, args.limit)
    counts = tally.counts
    print(
        f"{sum(counts.values())} files: {counts['accepted']} accepted (checked, {RUNS} runs"
        f" of {STEPS} steps), {counts['rejected']} rejected with a message,"
        f" {counts['crash']} crashes"
    )
    for text, detail in tally.crashes[: args.show]:
        print("-" * 72, "\n" + text[:2000], "\n" + detail, file=sys.stderr)
    return 1 if counts["crash"] else 0


if __name__ == "__main__":
    sys.exit(main())
