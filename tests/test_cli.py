"""Command-line contract: ``mresim run`` outputs and ``mresim validate`` / error exits."""

from __future__ import annotations

import csv
import json
import subprocess
import sys
from collections.abc import Callable
from importlib import metadata
from pathlib import Path
from typing import Any

import pytest
import yaml

from mresim_phys.cli import main
from mresim_phys.output.bench import DEFAULT_MAP, PRESETS, row_starts, team_scenario
from mresim_phys.render.layers import GLOBAL_LAYERS, ROBOT_LAYERS
from mresim_phys.scenario.load import load_scenario, validate_scenario
from mresim_phys.sim import Simulation

MakeScenario = Callable[..., Path]

REPO = Path(__file__).resolve().parent.parent
TEAM: dict[str, Any] = {"speed": 2, "radius": 1.0, "sensor": {"range": 30}, "comm_range": 20}


def cli(capsys: pytest.CaptureFixture[str], *args: str | Path) -> tuple[int, str, str]:
    """Run ``mresim *args`` in-process: (exit code, stdout, stderr)."""
    code = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


def read_metrics(out_dir: Path) -> list[dict[str, str]]:
    with (out_dir / "metrics.csv").open(newline="") as f:
        return list(csv.DictReader(f))


@pytest.fixture
def ran(
    scenario_file: MakeScenario, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> tuple[Path, Path]:
    """(scenario, output folder) of one quiet 5-step run."""
    path = scenario_file(steps=5)
    out = tmp_path / "out"
    code, _, _ = cli(capsys, "run", path, "--quiet", "--out", out)
    assert code == 0
    return path, out


# --- run outputs ------------------------------------------------------------------------


def test_run_writes_metrics_header(ran: tuple[Path, Path]) -> None:
    _, out = ran
    header = (out / "metrics.csv").read_text().splitlines()[0].split(",")
    assert header[:5] == ["step", "explored", "known_at_base", "distance", "alive"]
    for column in ("distance_A", "distance_B", "state_A", "state_B"):
        assert column in header


def test_run_writes_one_metrics_row_per_step_from_zero(ran: tuple[Path, Path]) -> None:
    _, out = ran
    assert [int(row["step"]) for row in read_metrics(out)] == list(range(6))


@pytest.mark.parametrize("column", ["explored", "known_at_base"])
def test_metric_fractions_are_bounded_and_never_decrease(
    ran: tuple[Path, Path], column: str
) -> None:
    _, out = ran
    values = [float(row[column]) for row in read_metrics(out)]
    assert all(0.0 <= v <= 1.0 for v in values)
    assert values == sorted(values)


def test_run_writes_summary_json(ran: tuple[Path, Path]) -> None:
    _, out = ran
    summary = json.loads((out / "summary.json").read_text())
    assert summary["steps"] == 5
    assert summary["wall_time_s"] >= 0
    last = read_metrics(out)[-1]
    assert summary["final_explored"] == float(last["explored"])
    assert summary["final_known_at_base"] == float(last["known_at_base"])
    for key in ("steps_to_explored", "steps_to_known_at_base"):
        assert set(summary[key]) == {"0.5", "0.9", "0.95"}
    rows = read_metrics(out)
    comm = summary["communication"]
    assert comm["comm_bytes"] == sum(int(r["comm_bytes"]) for r in rows) > 0
    assert comm["latency_max"] == max(float(r["latency_max"]) for r in rows)
    assert summary["robots"]["A"]["base_contact"] == int(last["base_contact_A"])


def test_run_writes_the_fully_resolved_scenario(ran: tuple[Path, Path]) -> None:
    path, out = ran
    written = out / "scenario.yaml"
    assert load_scenario(written) == load_scenario(path)
    raw = yaml.safe_load(written.read_text())
    assert "simulation" in raw
    assert "stop" in raw
    assert "min_frontier_size" in raw["team"]["strategy"]["params"]
    assert "min_frontier_size" in raw["robots"][0]["strategy"]["params"]
    assert Path(raw["map"]["image"]).is_absolute()


def test_steps_and_seed_flags_override_the_file(
    scenario_file: MakeScenario, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    code, _, _ = cli(
        capsys, "run", scenario_file(), "--steps", "3", "--seed", "7", "--quiet", "--out", out
    )
    assert code == 0
    summary = json.loads((out / "summary.json").read_text())
    assert (summary["steps"], summary["seed"]) == (3, 7)
    assert len(read_metrics(out)) == 4
    recorded = load_scenario(out / "scenario.yaml")
    assert (recorded.steps, recorded.seed) == (3, 7)


def test_quiet_run_prints_nothing_on_stdout(
    scenario_file: MakeScenario, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, out, _ = cli(capsys, "run", scenario_file(steps=2), "--quiet", "--out", tmp_path / "o")
    assert code == 0
    assert out == ""


def test_run_prints_a_summary_line(
    scenario_file: MakeScenario, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, out, _ = cli(capsys, "run", scenario_file(steps=2), "--out", tmp_path / "o")
    assert code == 0
    assert out.startswith("tiny seed 3: 2 steps")
    assert str(tmp_path / "o") in out


def test_run_defaults_to_runs_name_seed_under_cwd(
    scenario_file: MakeScenario,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    path = scenario_file(steps=2)
    monkeypatch.chdir(tmp_path)
    code, _, _ = cli(capsys, "run", path, "--quiet", "--seed", "4")
    assert code == 0
    assert (tmp_path / "runs" / "tiny" / "seed-4" / "summary.json").is_file()


# --- reproducibility --------------------------------------------------------------------


def run_metrics(capsys: pytest.CaptureFixture[str], path: Path, out: Path, seed: int) -> bytes:
    code, _, _ = cli(capsys, "run", path, "--seed", str(seed), "--quiet", "--out", out)
    assert code == 0
    return (out / "metrics.csv").read_bytes()


def test_same_seed_gives_byte_identical_metrics(
    scenario_file: MakeScenario, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = scenario_file(steps=5)
    first = run_metrics(capsys, path, tmp_path / "one", seed=2)
    second = run_metrics(capsys, path, tmp_path / "two", seed=2)
    assert first == second


def test_random_walk_with_another_seed_differs(
    scenario_file: MakeScenario, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = scenario_file(steps=5, team={**TEAM, "strategy": "random_walk"})
    first = run_metrics(capsys, path, tmp_path / "one", seed=1)
    second = run_metrics(capsys, path, tmp_path / "two", seed=2)
    assert first != second


# --- validate and user errors -----------------------------------------------------------


def test_validate_ok(scenario_file: MakeScenario, capsys: pytest.CaptureFixture[str]) -> None:
    path = scenario_file()
    code, out, err = cli(capsys, "validate", path)
    assert code == 0
    assert f"{path}: ok" in out
    assert err == ""


def test_validate_shipped_quickstart_from_another_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.chdir(tmp_path)
    code, out, _ = cli(capsys, "validate", REPO / "scenarios" / "01_quickstart.yaml")
    assert code == 0
    assert "ok" in out


def yaml_typo(make: MakeScenario) -> Path:
    path = make()
    path.write_text(path.read_text().replace("steps: 60", "steps: 60\n  oops: [1"))
    return path


def missing_file(make: MakeScenario) -> Path:
    return make().with_name("no_such_scenario.yaml")


def robot_in_wall(make: MakeScenario) -> Path:
    return make(robots=[{"name": "A", "start": [1, 1]}])


def unknown_strategy(make: MakeScenario) -> Path:
    return make(team={**TEAM, "strategy": "fronteir"})


@pytest.mark.parametrize(
    ("make_bad", "fragment"),
    [
        pytest.param(yaml_typo, "not valid YAML at line", id="yaml-typo"),
        pytest.param(missing_file, "does not exist", id="missing-file"),
        pytest.param(robot_in_wall, "robot 'A'", id="robot-in-wall"),
        pytest.param(unknown_strategy, "'frontier'", id="unknown-strategy"),
    ],
)
@pytest.mark.parametrize("command", ["validate", "run"])
def test_user_error_exits_2_with_a_message_and_no_traceback(
    scenario_file: MakeScenario,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    make_bad: Callable[[MakeScenario], Path],
    fragment: str,
    command: str,
) -> None:
    args: list[str | Path] = [command, make_bad(scenario_file)]
    if command == "run":
        args += ["--quiet", "--out", tmp_path / "out"]
    code, out, err = cli(capsys, *args)
    assert code == 2
    assert err.startswith("mresim: error:")
    assert fragment in err
    assert "Traceback" not in err
    assert out == ""


@pytest.mark.parametrize(
    ("flags", "fragment"),
    [
        pytest.param(["--steps", "abc"], "expected a whole number", id="steps-abc"),
        pytest.param(["--steps", "0"], "expected a number >= 1", id="steps-0"),
        pytest.param(["--seed", "-1"], "--seed", id="seed-negative"),
        pytest.param(["--bogus"], "unrecognized arguments: --bogus", id="unknown-flag"),
    ],
)
def test_bad_flags_exit_2_with_a_message(
    scenario_file: MakeScenario,
    capsys: pytest.CaptureFixture[str],
    flags: list[str],
    fragment: str,
) -> None:
    with pytest.raises(SystemExit) as info:
        main(["run", str(scenario_file()), *flags])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert "usage: mresim" in err
    assert "error:" in err
    assert fragment in err


def test_missing_command_exits_2(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as info:
        main([])
    assert info.value.code == 2
    assert "mresim: error:" in capsys.readouterr().err


def test_console_script_exits_nonzero_without_traceback(scenario_file: MakeScenario) -> None:
    script = Path(sys.executable).with_name("mresim")
    command = [str(script)] if script.is_file() else [sys.executable, "-m", "mresim_phys.cli"]
    path = scenario_file(stpes=5)
    done = subprocess.run(
        [*command, "validate", str(path)], capture_output=True, text=True, timeout=60
    )
    assert done.returncode == 2
    assert done.stderr.startswith("mresim: error:")
    assert "did you mean 'steps'" in done.stderr
    assert "Traceback" not in done.stderr


# --- output folders ---------------------------------------------------------------------


def quiet_run(
    capsys: pytest.CaptureFixture[str], path: Path, out: Path, *flags: str
) -> tuple[int, str, str]:
    return cli(capsys, "run", path, "--quiet", "--no-plots", "--out", out, *flags)


def test_a_rerun_of_the_same_scenario_replaces_the_old_run_whole(
    scenario_file: MakeScenario, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    assert quiet_run(capsys, scenario_file(steps=4), out, "--snapshot", "2")[0] == 0
    assert (out / "log").is_dir() and (out / "step-00002.png").is_file()
    (out / "metrics-replayed.csv").write_text("left by a replay\n")
    assert quiet_run(capsys, scenario_file(steps=3), out, "--no-log")[0] == 0
    assert sorted(p.name for p in out.iterdir()) == [
        "final.png",
        "metrics.csv",
        "scenario.yaml",
        "summary.json",
    ]
    assert json.loads((out / "summary.json").read_text())["steps"] == 3
    assert [p.name for p in tmp_path.iterdir() if ".tmp-" in p.name or ".old-" in p.name] == []


def test_a_run_of_another_scenario_is_kept_unless_overwrite(
    scenario_file: MakeScenario, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    assert quiet_run(capsys, scenario_file(steps=2), out)[0] == 0
    code, stdout, err = quiet_run(capsys, scenario_file(steps=2, name="other"), out)
    assert code == 2 and stdout == ""
    assert err.startswith("mresim: error:") and "another scenario, 'tiny'" in err
    assert "--overwrite" in err and "Traceback" not in err
    assert json.loads((out / "summary.json").read_text())["name"] == "tiny"
    assert quiet_run(capsys, scenario_file(steps=2, name="other"), out, "--overwrite")[0] == 0
    assert json.loads((out / "summary.json").read_text())["name"] == "other"


@pytest.mark.parametrize("kind", ["files", "junk summary", "a file"])
def test_a_folder_that_is_no_run_is_refused_unless_overwrite(
    scenario_file: MakeScenario, tmp_path: Path, capsys: pytest.CaptureFixture[str], kind: str
) -> None:
    out = tmp_path / "out"
    if kind == "a file":
        out.write_text("a file")
    else:
        out.mkdir()
        (out / ("notes.txt" if kind == "files" else "summary.json")).write_text("{not json")
    code, _, err = quiet_run(capsys, scenario_file(steps=2), out)
    assert code == 2
    assert str(out) in err and "--overwrite" in err
    assert quiet_run(capsys, scenario_file(steps=2), out, "--overwrite")[0] == 0
    assert json.loads((out / "summary.json").read_text())["name"] == "tiny"
    assert not (out / "notes.txt").exists()


def test_an_empty_folder_is_used(
    scenario_file: MakeScenario, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "out").mkdir()
    assert quiet_run(capsys, scenario_file(steps=2), tmp_path / "out")[0] == 0
    assert (tmp_path / "out" / "summary.json").is_file()


def test_the_current_folder_is_never_replaced(
    scenario_file: MakeScenario,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    path = scenario_file(steps=2)
    monkeypatch.chdir(tmp_path)
    for out in (".", str(tmp_path.parent)):
        code, _, err = quiet_run(capsys, path, Path(out), "--overwrite")
        assert code == 2
        assert "current folder" in err
    assert path.is_file()


def test_a_failing_run_leaves_the_old_run_and_no_temporary_folder(
    scenario_file: MakeScenario, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    assert quiet_run(capsys, scenario_file(steps=2), out)[0] == 0
    before = (out / "metrics.csv").read_bytes()
    code, _, err = quiet_run(capsys, scenario_file(steps=5), out, "--layers", "nope")
    assert code == 2 and "nope" in err
    assert (out / "metrics.csv").read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out", "rooms.png", "scenario.yaml"]


def test_outputs_are_written_under_temporary_names_and_renamed(
    scenario_file: MakeScenario, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    video = tmp_path / "videos" / "v.mp4"
    video.parent.mkdir()  # a folder a video path names must exist
    out = tmp_path / "out"
    assert quiet_run(capsys, scenario_file(steps=3), out, "--video", str(video))[0] == 0
    assert [p.name for p in video.parent.iterdir()] == ["v.mp4"]
    assert list(out.rglob(".*")) == []  # no temporary file left


# --- flags, bench, progress bar ---------------------------------------------------------


def test_version_comes_from_the_installed_package(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as info:
        main(["--version"])
    assert info.value.code == 0
    assert capsys.readouterr().out.strip() == f"mresim {metadata.version('mresim_phys')}"


def test_layers_help_lists_every_layer(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        main(["run", "--help"])
    text = " ".join(capsys.readouterr().out.split())  # argparse wraps lines
    for name in (*GLOBAL_LAYERS, *ROBOT_LAYERS):
        assert name in text


@pytest.mark.parametrize("counts", ["", ",", "4,,0"])
def test_bench_needs_team_sizes(capsys: pytest.CaptureFixture[str], counts: str) -> None:
    with pytest.raises(SystemExit) as info:
        main(["bench", "--robots", counts])
    assert info.value.code == 2
    assert "--robots" in capsys.readouterr().err


@pytest.mark.parametrize("robots", [1, 16, 32, 100])
def test_bench_teams_of_any_size_start_clear_of_walls(robots: int) -> None:
    scenario = validate_scenario(team_scenario(robots, DEFAULT_MAP, steps=1))
    sim = Simulation(scenario)  # checks every start against the walls
    positions = [r.position for r in sim.robots]
    assert len(set(positions)) == robots
    if robots <= 16:  # the usual teams keep their rows of eight
        assert positions == row_starts(robots)


def test_bench_runs_32_robots(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = cli(capsys, "bench", "--robots", "32", "--warmup", "0", "--steps", "1")
    assert code == 0, err
    assert out.splitlines()[2].split()[:2] == ["frontier", "32"]


def test_bench_compares_strategies_and_rejects_unknown_ones(
    capsys: pytest.CaptureFixture[str],
) -> None:
    args = ("bench", "--robots", "2", "--warmup", "0", "--steps", "1")
    code, out, err = cli(capsys, *args, "--strategies", "frontier,min_pos")
    assert code == 0, err
    assert [line.split()[0] for line in out.splitlines()[2:4]] == ["frontier", "min_pos"]
    with pytest.raises(SystemExit) as info:
        cli(capsys, *args, "--strategies", "frontir")
    err = capsys.readouterr().err
    assert info.value.code == 2 and "frontier" in err and "Traceback" not in err


def test_the_progress_bar_ends_at_the_steps_run(
    scenario_file: MakeScenario, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = scenario_file(steps=200, stop={"explored": 0.6})
    code, _, err = cli(capsys, "run", path, "--no-plots", "--out", tmp_path / "o")
    assert code == 0
    steps = json.loads((tmp_path / "o" / "summary.json").read_text())["steps"]
    assert 0 < steps < 200
    last = err.replace("\r", "\n").strip().splitlines()[-1]
    assert f"{steps}/{steps}" in last and "100%" in last


def test_an_unknown_robot_is_a_key_error_naming_the_team(scenario_file: MakeScenario) -> None:
    sim = Simulation.from_yaml(scenario_file(steps=1))
    assert sim.robot("B").name == "B"
    with pytest.raises(KeyError) as info:
        sim.robot("Z")
    assert str(info.value) == "no robot 'Z' in this run; its robots are 'A', 'B'"


@pytest.mark.parametrize("preset", ["original", "rooms"])
def test_bench_presets_at_the_originals_settings(
    capsys: pytest.CaptureFixture[str], preset: str
) -> None:
    """The original's settings on its layouts, shipped with the package: any team fits."""
    chosen = PRESETS[preset]
    assert chosen.map_path.is_file() and chosen.team["speed"] == 10
    scenario = validate_scenario(team_scenario(32, chosen.map_path, 1, chosen))
    sim = Simulation(scenario)  # checks every start against the walls
    assert len({r.position for r in sim.robots}) == 32
    body = sim.robots[0].body
    assert body is not None and body.laser.range == 200 and body.radius == 0.5
    code, out, err = cli(capsys, "bench", "--preset", preset, "--robots", "2", "--warmup", "0",
                         "--steps", "1")  # fmt: skip
    assert code == 0, err
    assert f"--preset {preset}" in out and out.splitlines()[2].split()[1] == "2"
