"""Scenario, map and team input found broken on purpose, each refused with a one-paragraph
message (exit 2) or run as documented: defaults kept when the command line overrides
nothing, a file's own wrong value not hidden by an override, ``!!binary`` text, events after
the step cap, doors of no length, non-finite ROS map numbers, maps too big to build, team
files that are devices or start robots in walls, and signals while the command starts."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest
import yaml
from PIL import Image

from mresim_phys.cli import main
from mresim_phys.errors import MapError, ScenarioError
from mresim_phys.scenario.load import load_scenario
from mresim_phys.scenario.readers import load_image_map, load_ros_map, load_text_map

ROOT = Path(__file__).resolve().parent.parent
SMALL = ROOT / "maps" / "small_rooms.png"  # 160x120


def scenario(folder: Path, **fields: Any) -> Path:
    """A small valid scenario (without ``seed`` and ``steps``) with ``fields`` changed;
    a field given None is left out."""
    data: dict[str, Any] = {
        "name": "hard",
        "map": {"image": str(SMALL)},
        "base_station": {"position": [20, 60], "comm_range": 40},
        "robots": [{"name": "A", "start": [22, 62]}],
    }
    data.update(fields)
    path = folder / "hard.yaml"
    path.write_text(yaml.safe_dump({k: v for k, v in data.items() if v is not None}), "utf-8")
    return path


def refused(args: list[str], capsys: pytest.CaptureFixture[str], *words: str) -> str:
    """Run ``mresim args``: exit 2, one message holding ``words``, no traceback."""
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and err.startswith("mresim: error:"), err
    for word in words:
        assert word in err, err
    return err


# --- defaults and overrides ---------------------------------------------------------------


def test_a_scenario_without_seed_or_steps_runs_with_the_defaults(tmp_path: Path) -> None:
    path = scenario(tmp_path)
    assert main(["validate", str(path)]) == 0
    loaded = load_scenario(path, seed=None, steps=None)  # what `mresim run` passes
    assert (loaded.seed, loaded.steps) == (0, 3000)
    assert main(["run", str(path), "--steps", "2", "--out", str(tmp_path / "o"), "--quiet"]) == 0
    assert main(["run", str(path), "--seed", "4", "--out", str(tmp_path / "p"), "--quiet",
                 "--steps", "2"]) == 0  # fmt: skip


def test_an_override_does_not_hide_the_files_own_wrong_value(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = scenario(tmp_path, steps=-5)
    refused(["run", str(path), "--steps", "3", "--out", str(tmp_path / "o")], capsys,
            "hard.yaml", "steps")  # fmt: skip
    assert not (tmp_path / "o").exists()
    with pytest.raises(ScenarioError, match="steps"):
        load_scenario(scenario(tmp_path, steps="many"), steps=3)


def test_binary_yaml_is_not_text(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = scenario(tmp_path)
    text = path.read_text("utf-8").replace("name: hard", "name: !!binary aGVsbG8=")
    path.write_text(text, "utf-8")
    refused(["validate", str(path)], capsys, "hard.yaml", "name", "!!binary")


def test_an_event_after_the_step_cap_is_refused_but_a_shorter_run_may_cut_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    late = scenario(tmp_path, steps=50, events=[{"step": 100, "fail": "A"}])
    refused(["validate", str(late)], capsys, "events[0] (step 100)", "steps: 50")
    fine = scenario(tmp_path, steps=200, events=[{"step": 100, "fail": "A"}])
    assert main(["run", str(fine), "--steps", "3", "--out", str(tmp_path / "o"), "--quiet"]) == 0


@pytest.mark.parametrize("ends", [[[30, 30], [30, 30]], [[30, 30], [30.5, 30.5]]])
def test_a_door_of_no_length_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], ends: list[list[float]]
) -> None:
    path = scenario(tmp_path, doors=[{"name": "d", "between": ends}])
    refused(["validate", str(path)], capsys, "doors[0]", "less than a cell apart")


# --- maps -------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("line", "word"),
    [
        ("resolution: .nan", "resolution"),
        ("resolution: .inf", "resolution"),
        ("resolution: -.inf", "resolution"),
        ("resolution: 1e-300", "resolution"),
        ("resolution: 1e300", "resolution"),
        ("resolution: 0.1\norigin: [.nan, 0, 0]", "origin"),
        ("resolution: 0.1\norigin: [0, .inf, 0]", "origin"),
        ("resolution: 0.1\norigin: [0, 0, 1e308]", "origin"),
    ],
)
def test_a_ros_map_with_non_finite_numbers_is_refused(tmp_path: Path, line: str, word: str) -> None:
    Image.open(SMALL).save(tmp_path / "m.pgm")
    (tmp_path / "m.yaml").write_text(f"image: m.pgm\n{line}\n", "utf-8")
    with pytest.raises(MapError, match=rf"m\.yaml: '{word}'"):
        load_ros_map(tmp_path / "m.yaml")


def test_a_huge_image_is_refused_from_its_header(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    big = tmp_path / "big.png"
    Image.new("1", (13000, 13000), 1).save(big)
    assert big.stat().st_size < 300_000
    started = time.perf_counter()
    with pytest.raises(MapError, match=r"13,000 x 13,000 = 169,000,000 cells, over the limit"):
        load_image_map(big)
    assert time.perf_counter() - started < 2.0
    path = scenario(tmp_path, map={"image": str(big)})
    refused(["validate", str(path)], capsys, "big.png", "map.max_cells")


def test_map_max_cells_sets_the_bound(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = scenario(tmp_path, map={"image": str(SMALL), "max_cells": 160 * 120 - 1})
    refused(["validate", str(path)], capsys, "160 x 120 = 19,200 cells")
    path = scenario(tmp_path, map={"image": str(SMALL), "max_cells": 160 * 120})
    assert main(["validate", str(path)]) == 0


def test_a_text_map_too_big_is_refused_before_it_is_read(tmp_path: Path) -> None:
    header = tmp_path / "header.txt"
    header.write_text("100000\n100000\n0101\n", "utf-8")
    with pytest.raises(MapError, match="10,000,000,000 cells, over the limit"):
        load_text_map(header)
    long = tmp_path / "long.txt"
    long.write_text("2\n2\n" + "0" * 400 + "\n", "utf-8")
    with pytest.raises(MapError, match="more than a map of at most 100 cells"):
        load_text_map(long, max_cells=100)


# --- team files -------------------------------------------------------------------------

TEAM = "1 base 20 60 0 100 100 0 BaseStation 0 0\n2 A 22 62 0 100 100 0 Explorer 1 0\n"


def test_import_team_refuses_devices_pipes_and_bad_starts(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    refused(["import-team", "/dev/zero", "--map", str(SMALL)], capsys, "/dev/zero", "regular")
    fifo = tmp_path / "team.fifo"
    os.mkfifo(fifo)
    refused(["import-team", str(fifo), "--map", str(SMALL)], capsys, "team.fifo", "regular")
    team = tmp_path / "team.txt"
    for line, words in [
        ("3 B 1 1 0 100 100 0 Explorer 1 0\n", ("team.txt", "'B'", "wall")),
        ("3 B 500 62 0 100 100 0 Explorer 1 0\n", ("team.txt", "'B'", "outside the 160x120")),
    ]:
        team.write_text(TEAM + line, "utf-8")
        refused(["import-team", str(team), "--map", str(SMALL)], capsys, *words)
    team.write_text(TEAM, "utf-8")
    refused(["import-team", str(team), "--map", "nowhere.png"], capsys, "nowhere.png")
    out = tmp_path / "team.yaml"
    assert main(["import-team", str(team), "--map", str(SMALL), "--out", str(out)]) == 0
    assert main(["validate", str(out)]) == 0


# --- signals while the command starts ---------------------------------------------------


def handling_sigterm(pid: int, timeout: float = 30.0) -> None:
    """Wait until process ``pid`` catches SIGTERM (``SigCgt`` in ``/proc/PID/status``):
    ``launch.py`` installs its handler before the heavy imports start. A fixed sleep of
    0.5 s let a fast start reach the run itself, which stops cleanly with status 0."""
    deadline = time.monotonic() + timeout
    bit = 1 << (signal.SIGTERM - 1)
    while time.monotonic() < deadline:
        fields = dict(
            line.split(":", 1)
            for line in Path(f"/proc/{pid}/status").read_text(encoding="utf-8").splitlines()
        )
        if fields["State"].split()[0] in ("Z", "X"):
            raise AssertionError(f"process {pid} ended before it caught SIGTERM")
        if int(fields["SigCgt"], 16) & bit:
            return
        time.sleep(0.002)
    raise AssertionError(f"process {pid} never caught SIGTERM")


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="reads /proc")
@pytest.mark.parametrize(("sig", "status"), [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_signal_while_mresim_starts_exits_with_a_line(
    tmp_path: Path, sig: signal.Signals, status: int
) -> None:
    path = scenario(tmp_path, steps=5)
    command = [sys.executable, "-m", "mresim_phys.launch", "run", str(path), "--quiet",
               "--out", str(tmp_path / "o")]  # fmt: skip
    env = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1"}
    process = subprocess.Popen(
        command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )  # fmt: skip
    handling_sigterm(process.pid)  # launch.py is up; numpy, numba, pymunk are importing
    process.send_signal(sig)
    _, err = process.communicate(timeout=60)
    assert process.returncode == status, err
    assert "Traceback" not in err and err.strip().startswith("mresim:"), err
    assert not (tmp_path / "o" / "summary.json").exists()


def test_ctrl_c_while_the_command_line_is_parsed_exits_with_a_line() -> None:
    """The light command line is parsed in a blink, so a Ctrl-C can land there, before
    the command's own handling: one line and status 130, never a traceback."""
    code = (
        "import sys\n"
        "import mresim_phys.cli as cli\n"
        "from mresim_phys import launch\n"
        "def interrupted(*args, **kwargs):\n"
        "    raise KeyboardInterrupt\n"
        "cli.make_parser = interrupted\n"
        "sys.exit(launch.main(['run', 'x.yaml']))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 130, done.stderr
    assert done.stderr == "mresim: interrupted while starting\n"


def test_a_video_path_in_a_missing_folder_is_refused_and_no_folder_made(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = scenario(tmp_path)
    video = tmp_path / "nowhere" / "deeper" / "x.mp4"
    args = ["run", str(path), "--steps", "2", "--out", str(tmp_path / "o"), "--quiet"]
    refused([*args, "--video", str(video)], capsys, "hard.yaml", "render.video", "nowhere")
    assert not (tmp_path / "nowhere").exists() and not (tmp_path / "o").exists()
    path = scenario(tmp_path, render={"video": str(video)})
    refused(args, capsys, "render.video")
    assert not (tmp_path / "nowhere").exists()


def test_a_replay_video_in_a_missing_folder_is_refused_and_no_folder_made(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    run = tmp_path / "run"
    assert main(["run", str(scenario(tmp_path)), "--steps", "2", "--out", str(run), "--quiet"]) == 0
    video = tmp_path / "nowhere" / "x.mp4"
    refused(["replay", str(run), "--video", str(video)], capsys, "render.video", "nowhere")
    assert not (tmp_path / "nowhere").exists()
