"""Malformed scenarios never crash: every file runs or is rejected with a message (exit 2).

Hypothesis mutates valid base scenarios (``tools/fuzz_scenarios.py`` holds the
generators and the judge) and a fixed corpus covers each class of mistake found
by hand: non-finite and absurd numbers, booleans for numbers, duplicate keys,
deep nesting, path-escaping names, broken plugin references, snapshots past the
step cap, a base station in a wall, robots overlapping at their starts.
"""

from __future__ import annotations

import copy
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import yaml
from tool_modules import load_tool

ROOT = Path(__file__).resolve().parent.parent


fuzz = load_tool("fuzz_scenarios")
GENERATED = 300  # files generated in the suite; tools/fuzz_scenarios.py runs more


@pytest.fixture(scope="module")
def work(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder holding the small map every base scenario names."""
    return fuzz.prepare(tmp_path_factory.mktemp("fuzz"))


def test_generated_scenarios_run_or_are_rejected_with_a_message(work: Path) -> None:
    tally = fuzz.fuzz(GENERATED, work / "generated", seed=None)  # derandomized: reproducible
    counts = tally.counts
    assert not tally.crashes, "\n\n".join(f"{text}\n{detail}" for text, detail in tally.crashes)
    assert sum(counts.values()) >= GENERATED
    assert counts["accepted"] >= 20 and counts["rejected"] >= 100, counts


# --- a fixed corpus, one entry per class of mistake --------------------------------------

Change = Callable[[dict[str, Any]], None]


def setting(path: str, value: Any) -> Change:
    """A change setting the dotted ``path`` (list indices as numbers) to ``value``."""

    def change(data: dict[str, Any]) -> None:
        *parents, leaf = (int(k) if k.isdigit() else k for k in path.split("."))
        for key in parents:
            data = data.setdefault(key, {}) if isinstance(key, str) else data[key]
        data[leaf] = value  # type: ignore[index]

    return change


def crowd(data: dict[str, Any]) -> None:
    """40 robots on one start point, bodies blocking each other."""
    data["robots"] = [{"name": f"R{i}", "start": [66, 52]} for i in range(40)]
    data["simulation"] = {"robots_block": True}


INF, NAN = float("inf"), float("nan")
REJECTED: list[Any] = [
    pytest.param(setting("team.comm_range", INF), "team.comm_range", id="comm_range-inf"),
    pytest.param(setting("team.comm_range", 1e30), "team.comm_range", id="comm_range-1e30"),
    pytest.param(setting("team.comm_range", 1e308), "team.comm_range", id="comm_range-1e308"),
    pytest.param(setting("base_station.comm_range", INF), "base_station.comm_range", id="base"),
    pytest.param(setting("team.wall_margin", INF), "team.wall_margin", id="wall_margin-inf"),
    pytest.param(setting("team.wall_margin", 1e30), "team.wall_margin", id="wall_margin-1e30"),
    pytest.param(setting("team.sensor.range", 1e20), "team.sensor.range", id="range-1e20"),
    pytest.param(setting("team.sensor.range", INF), "team.sensor.range", id="range-inf"),
    pytest.param(setting("team.speed", INF), "team.speed", id="speed-inf"),
    pytest.param(setting("team.sensor.noise_std", INF), "noise_std", id="noise-inf"),
    pytest.param(setting("robots.0.heading_deg", NAN), "robots[0].heading_deg", id="heading-nan"),
    pytest.param(setting("robots.0.start", [INF, 3]), "robots[0].start", id="start-inf"),
    pytest.param(
        setting("communication", {"model": "path_loss", "params": {"cutoff_dbm": NAN}}),
        "communication.params.cutoff_dbm",
        id="cutoff-nan",
    ),
    pytest.param(
        setting("communication", {"model": "path_loss", "params": {"reference_dbm": 1e6}}),
        "communication.params.reference_dbm",
        id="reference-dbm-huge",
    ),
    pytest.param(setting("team.comm_power_dbm", 1000), "team.comm_power_dbm", id="power-1000"),
    pytest.param(
        setting("team.strategy", {"name": "frontier", "params": {"horizon": INF}}),
        "team.strategy.params.horizon",
        id="strategy-param-inf",
    ),
    pytest.param(
        setting("team.planner", {"name": "topological", "params": {"rebuild_fraction": NAN}}),
        "team.planner.params.rebuild_fraction",
        id="planner-param-nan",
    ),
    pytest.param(setting("team.speed", True), "team.speed", id="speed-true"),
    pytest.param(setting("seed", False), "seed", id="seed-false"),
    pytest.param(setting("robots.0.start", [True, 3]), "robots[0].start", id="start-bool"),
    pytest.param(
        setting("team.strategy", {"name": "frontier", "params": {"replan_interval": True}}),
        "team.strategy.params.replan_interval",
        id="strategy-param-bool",
    ),
    pytest.param(
        setting("events", [{"step": 1, "until": True, "blackout": ["A"]}]),
        "events[0].until",
        id="event-bool",
    ),
    pytest.param(setting("name", "."), "name", id="name-dot"),
    pytest.param(setting("name", ".."), "name", id="name-dotdot"),
    pytest.param(setting("robots.1.name", ".."), "robots[1].name", id="robot-dotdot"),
    pytest.param(setting("team.strategy", ":"), "team.strategy", id="strategy-colon"),
    pytest.param(setting("team.strategy", "a:"), "team.strategy", id="strategy-no-class"),
    pytest.param(setting("team.strategy", ":B"), "team.strategy", id="strategy-no-module"),
    pytest.param(setting("team.strategy", "..x:Y"), "team.strategy", id="strategy-relative"),
    pytest.param(setting("team.strategy", "os:path"), "team.strategy", id="strategy-module"),
    pytest.param(
        setting("team.strategy", "mresim_phys.cli:main"), "team.strategy", id="strategy-function"
    ),
    pytest.param(setting("team.planner", "no_such_pkg:P"), "team.planner", id="planner-import"),
    pytest.param(setting("communication.model", ":"), "communication.model", id="comm-colon"),
    pytest.param(setting("render.snapshots", [-1]), "render.snapshots", id="snapshot-negative"),
    pytest.param(setting("render.snapshots", [2, 9]), "render.snapshots", id="snapshot-late"),
    pytest.param(setting("render.layers", "walls,Z:path"), "render.layers", id="layers-robot"),
    pytest.param(setting("render.layers", "wals"), "render.layers", id="layers-unknown"),
    pytest.param(
        setting("base_station.position", [1, 1]), "base_station.position", id="base-in-wall"
    ),
    pytest.param(
        setting("base_station.position", [500, 1]), "base_station.position", id="base-outside"
    ),
    pytest.param(crowd, "'R0' and 'R1'", id="robots-overlap"),
    pytest.param(setting("map.image", "gone.png"), "map.image", id="map-missing"),
    pytest.param(
        setting("communication", {"model": "path_loss", "params": {"exponent": 1e-30}}),
        "communication.params.exponent",
        id="path-loss-exponent-tiny",
    ),
]


def write(folder: Path, name: str, text: str) -> Path:
    path = folder / f"{name}.yaml"
    path.write_text(text, encoding="utf-8")
    return path


def run_cli(path: Path, out: Path, capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    """``mresim run PATH --steps 3`` in-process: its exit code and its stderr."""
    from mresim_phys.cli import main

    capsys.readouterr()
    args = ["run", str(path), "--steps", "3", "--quiet", "--no-plots", "--out", str(out)]
    code = main(args)
    return code, capsys.readouterr().err


@pytest.mark.parametrize(("change", "fragment"), REJECTED)
def test_each_class_of_mistake_is_rejected_naming_file_and_field(
    work: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    change: Change,
    fragment: str,
) -> None:
    data = copy.deepcopy(fuzz.PLAIN)
    change(data)
    path = write(work, tmp_path.name, yaml.safe_dump(data, sort_keys=False))
    code, err = run_cli(path, tmp_path / "out", capsys)
    assert code == 2, err
    assert err.startswith(f"mresim: error: {path}") and fragment in err, err
    assert "Traceback" not in err


PLAIN_TEXT = yaml.safe_dump(fuzz.PLAIN, sort_keys=False)
RAW: list[Any] = [
    pytest.param(PLAIN_TEXT + "seed: 5\n", ["'seed' appears twice", "line"], id="dup-seed"),
    pytest.param(
        PLAIN_TEXT + "events: []\nevents: [{step: 1, fail: A}]\n",
        ["'events' appears twice"],
        id="dup-events",
    ),
    pytest.param(
        PLAIN_TEXT.replace("  speed: 3\n", "  speed: 3\n  speed: 4\n"),
        ["'speed' appears twice (first at line"],
        id="dup-nested",
    ),
    pytest.param(
        PLAIN_TEXT + "deep: " + "[" * 5000 + "]" * 5000 + "\n", ["nested too deeply"], id="deep"
    ),
    pytest.param(PLAIN_TEXT.replace("seed: 1", "seed: 2001-13-01"), ["line 2", "month"], id="date"),
    pytest.param(PLAIN_TEXT.replace("name: fuzz", "name: [unclosed"), ["line"], id="syntax"),
]


@pytest.mark.parametrize(("text", "fragments"), RAW)
def test_yaml_mistakes_are_rejected_with_the_line(
    work: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str, fragments: list[str]
) -> None:
    path = write(work, tmp_path.name, text)
    code, err = run_cli(path, tmp_path / "out", capsys)
    assert code == 2 and err.startswith(f"mresim: error: Scenario file {path}"), err
    assert all(f in err for f in fragments), err


ACCEPTED: list[Any] = [
    pytest.param(setting("team.comm_range", 100_000), id="comm_range-max"),
    pytest.param(setting("base_station.comm_range", 100_000), id="base-range-max"),
    pytest.param(setting("team.sensor.range", 100_000), id="sensor-range-max"),
    pytest.param(setting("team.speed", 1000), id="speed-max"),
    pytest.param(setting("team.wall_margin", 1000), id="wall_margin-max"),
    pytest.param(setting("robots.0.heading_deg", -720.5), id="heading-any"),
    pytest.param(
        setting(
            "communication",
            {"model": "path_loss", "params": {"reference_dbm": -30, "cutoff_dbm": -120}},
        ),
        id="dbm-strong-radio",
    ),
    pytest.param(
        setting(
            "communication",
            {"model": "path_loss", "params": {"reference_dbm": 300, "cutoff_dbm": -300}},
        ),
        id="dbm-bounds",
    ),
    pytest.param(
        setting(
            "communication",
            {"model": "path_loss", "params": {"exponent": 1.0, "reference_dbm": 300}},
        ),
        id="path-loss-exponent-smallest",
    ),
    pytest.param(setting("render.snapshots", [0, 3]), id="snapshots-within"),
    pytest.param(setting("simulation", {"robots_block": True}), id="robots-apart"),
]


@pytest.mark.parametrize("change", ACCEPTED)
def test_large_but_sensible_values_run(
    work: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], change: Change
) -> None:
    data = copy.deepcopy(fuzz.PLAIN)
    change(data)
    path = write(work, tmp_path.name, yaml.safe_dump(data, sort_keys=False))
    code, err = run_cli(path, tmp_path / "out", capsys)
    assert code == 0, err
    assert fuzz.judge_run(tmp_path / "out").kind == "accepted"


def test_merge_keys_may_override_without_counting_as_duplicates(
    work: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    robots = "robots:\n  - &a {name: A, start: [66, 52], speed: 2}\n  - <<: *a\n    name: B\n"
    text = PLAIN_TEXT.split("robots:")[0] + robots + "    start: [66, 68]\n"
    path = write(work, tmp_path.name, text)
    code, err = run_cli(path, tmp_path / "out", capsys)
    assert code == 0, err


@pytest.mark.parametrize("base", range(len(fuzz.BASES)))
def test_every_base_scenario_of_the_fuzzer_runs(
    work: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], base: int
) -> None:
    path = write(work, tmp_path.name, yaml.safe_dump(fuzz.BASES[base], sort_keys=False))
    code, err = run_cli(path, tmp_path / "out", capsys)
    assert code == 0, err
