"""Videos, pictures, run logs and replay, as a user runs them from the command line."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml

from mresim_phys.cli import main
from mresim_phys.localization.feature import LOCALIZATION
from mresim_phys.output.runlog import RunLog
from mresim_phys.render import Renderer, frame_scale, parse_layers

ScenarioFile = Callable[..., Path]
ROOT = Path(__file__).resolve().parent.parent


def run(path: Path, out: Path, *flags: str) -> None:
    assert main(["run", str(path), "--out", str(out), "--quiet", "--no-plots", *flags]) == 0


def read_png(path: Path) -> np.ndarray:
    image = cv2.imread(str(path), cv2.IMREAD_COLOR)
    assert image is not None, path
    return image


def test_run_writes_video_snapshots_final_picture_and_log(
    scenario_file: ScenarioFile, tmp_path: Path
) -> None:
    video = tmp_path / "live.mp4"
    run(scenario_file(steps=20), tmp_path / "run", "--video", str(video), "--snapshot", "5,10")
    capture = cv2.VideoCapture(str(video))
    frames = int(capture.get(cv2.CAP_PROP_FRAME_COUNT))
    width, height = capture.get(cv2.CAP_PROP_FRAME_WIDTH), capture.get(cv2.CAP_PROP_FRAME_HEIGHT)
    capture.release()
    assert frames == 21  # step 0 and 20 steps
    assert (width, height) == (640, 480)  # an 80x60 map, scaled up to a 640-pixel side
    for name in ("step-00005.png", "step-00010.png", "final.png"):
        assert read_png(tmp_path / "run" / name).shape == (480, 640, 3)
    assert (tmp_path / "run" / "log").is_dir()


@pytest.mark.parametrize(
    "comm",
    [{"model": "disk"}, {"model": "path_loss", "control": {"model": "disk", "range": 90}}],
    ids=["disk circles", "path-loss regions"],
)
def test_replayed_frames_equal_live_frames(
    scenario_file: ScenarioFile, tmp_path: Path, comm: dict[str, object]
) -> None:
    out = tmp_path / "run"
    path = scenario_file(steps=25, communication=comm)
    run(path, out, "--snapshot", "7,25", "--layers", "all", "--scale", "2")
    code = main(["replay", str(out), "--snapshot", "7,25", "--layers", "all", "--scale", "2"])
    assert code == 0
    for step in (7, 25):
        live = read_png(out / f"step-{step:05d}.png")
        replayed = read_png(out / f"replay-step-{step:05d}.png")
        assert np.array_equal(live, replayed)


def test_replayed_planner_views_equal_live_frames(tmp_path: Path) -> None:
    """Skeletons (topological planners) and every other layer replay pixel for pixel."""
    out, flags = tmp_path / "run", ["--snapshot", "30", "--layers", "all"]
    run(ROOT / "scenarios" / "09_planners.yaml", out, "--steps", "30", *flags)
    assert main(["replay", str(out), *flags]) == 0
    live = read_png(out / "step-00030.png")
    assert np.array_equal(live, read_png(out / "replay-step-00030.png"))
    last = list(RunLog.open(out / "log").snapshots())[-1]  # the views of the last step
    skeletons = [r.name for r in last.robots if r.skeleton is not None and r.skeleton.any()]
    assert skeletons == ["C", "D"]  # the topological planners' views were logged


def test_replayed_believed_poses_equal_live_frames(tmp_path: Path) -> None:
    """A run with odometry drift: the believed poses, their ellipses and the paths drawn
    from them replay pixel for pixel (the quickstart with ``team.localization``)."""
    data = yaml.safe_load((ROOT / "scenarios" / "01_quickstart.yaml").read_text())
    data["map"]["image"] = str((ROOT / "maps" / "small_rooms.png").resolve())
    data["team"]["localization"] = {"odometry": {"alpha": [0.001, 0.00001, 0.001, 0.00001]}}
    path, out, flags = tmp_path / "drift.yaml", tmp_path / "run", ["--snapshot", "20,40"]
    path.write_text(yaml.safe_dump(data))
    run(path, out, "--steps", "40", "--video", str(tmp_path / "live.mp4"), *flags)
    assert main(["replay", str(out), *flags]) == 0
    for step in (20, 40):
        live = read_png(out / f"step-{step:05d}.png")
        assert np.array_equal(live, read_png(out / f"replay-step-{step:05d}.png"))
    last = list(RunLog.open(out / "log").snapshots())[-1]
    beliefs = [LOCALIZATION.of(robot) for robot in last.robots]
    assert all(b is not None and b.error > 0.1 and b.sigma > 0.1 for b in beliefs)
    shape = last.truth.shape
    without = Renderer(shape, parse_layers("default,-localization"), frame_scale(shape, 1))
    assert not np.array_equal(live, without.render(last))  # the believed poses are drawn


@pytest.mark.parametrize("model", ["disk", "path_loss"])
def test_replay_follows_changes_of_the_world(
    scenario_file: ScenarioFile, tmp_path: Path, model: str
) -> None:
    """The door closes at step 8 and half opens at step 20 (``cells`` events): replayed
    frames (walls, regions through them) and metrics equal the live ones."""
    door, half = [40, 25, 42, 37], [40, 25, 42, 31]
    events = [{"step": 8, "cells": door}, {"step": 20, "cells": half, "occupied": False}]
    team = {"speed": 2, "radius": 1.0, "sensor": {"range": 30}, "comm_range": 50}
    radio = {"position": [8, 30], "comm_range": 50}  # regions reach through the door
    changes = {"events": events, "team": team, "base_station": radio}
    path = scenario_file(steps=30, communication={"model": model}, **changes)
    out, steps = tmp_path / "run", (7, 8, 19, 20, 30)
    flags = ["--snapshot", ",".join(map(str, steps)), "--layers", "all", "--scale", "2"]
    run(path, out, *flags)
    assert main(["replay", str(out), *flags, "--metrics"]) == 0
    assert (out / "metrics-replayed.csv").read_bytes() == (out / "metrics.csv").read_bytes()
    for step in steps:
        live = read_png(out / f"step-{step:05d}.png")
        assert np.array_equal(live, read_png(out / f"replay-step-{step:05d}.png")), step


def test_path_loss_regions_are_drawn_where_circles_would_be(
    scenario_file: ScenarioFile, tmp_path: Path
) -> None:
    frames = {}
    radio = {"position": [8, 30], "comm_range": 50}  # reaches through the wall at x = 40
    for model in ("disk", "path_loss"):
        out = tmp_path / model
        path = scenario_file(steps=3, communication={"model": model}, base_station=radio)
        run(path, out, "--snapshot", "3", "--layers", "all", "--scale", "4")
        frames[model] = read_png(out / "step-00003.png")
    assert not np.array_equal(frames["disk"], frames["path_loss"])


def test_replayed_metrics_equal_live_metrics_with_a_failure(
    scenario_file: ScenarioFile, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "run"
    run(scenario_file(steps=40, events=[{"step": 10, "fail": "B"}]), out)
    assert main(["replay", str(out), "--metrics"]) == 0
    assert "identical" in capsys.readouterr().out
    assert (out / "metrics-replayed.csv").read_bytes() == (out / "metrics.csv").read_bytes()


def test_replay_renders_a_video_with_other_layers(
    scenario_file: ScenarioFile, tmp_path: Path
) -> None:
    out = tmp_path / "run"
    run(scenario_file(steps=12), out)
    video = tmp_path / "replay.webm"
    assert (
        main(["replay", str(out), "--video", str(video), "--layers", "default,B:free_space"]) == 0
    )
    capture = cv2.VideoCapture(str(video))
    assert int(capture.get(cv2.CAP_PROP_FRAME_COUNT)) in (13, 0)  # webm may not report a count
    ok, frame = capture.read()
    capture.release()
    assert ok and frame.shape == (480, 640, 3)


def test_bad_layers_and_missing_logs_are_clear_errors(
    scenario_file: ScenarioFile, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "run"
    run(scenario_file(steps=3), out, "--no-log")
    assert main(["replay", str(out)]) == 2
    assert "log" in capsys.readouterr().err
    assert (
        main(
            [
                "run",
                str(scenario_file()),
                "--out",
                str(tmp_path / "x"),
                "--quiet",
                "--layers",
                "frontierz",
            ]
        )
        == 2
    )
    err = capsys.readouterr().err
    assert "frontiers" in err and "Traceback" not in err


def test_summary_still_written_with_video(scenario_file: ScenarioFile, tmp_path: Path) -> None:
    out = tmp_path / "run"
    run(scenario_file(steps=5), out, "--video", str(tmp_path / "v.mp4"))
    summary = json.loads((out / "summary.json").read_text())
    assert summary["steps"] == 5


@pytest.mark.parametrize(
    ("change", "fragment"),
    [
        pytest.param({"chunk_steps": 0}, "chunk_steps 0", id="chunk-0"),
        pytest.param({"steps": "5"}, "steps '5'", id="steps-text"),
        pytest.param({"shape": [1]}, "shape [1]", id="shape"),
        pytest.param({"agents": [1, 2]}, "agent 1", id="agents"),
        pytest.param({"starts": [[1]]}, "starts", id="starts"),
        pytest.param({"name": None}, "name None", id="name"),
    ],
)
def test_a_damaged_log_is_a_clear_error(
    scenario_file: ScenarioFile,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    change: dict[str, object],
    fragment: str,
) -> None:
    out = tmp_path / "run"
    run(scenario_file(steps=3), out)
    meta_path = out / "log" / "meta.json"
    meta_path.write_text(json.dumps(json.loads(meta_path.read_text()) | change))
    capsys.readouterr()
    assert main(["replay", str(out), "--metrics"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("mresim: error:") and "meta.json" in err and fragment in err


def test_a_damaged_render_block_is_a_clear_error(
    scenario_file: ScenarioFile, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "run"
    run(scenario_file(steps=3), out)
    (out / "scenario.yaml").write_text("render: 5\n")
    capsys.readouterr()
    assert main(["replay", str(out), "--metrics"]) == 2
    assert "scenario.yaml: 'render' is 5" in capsys.readouterr().err
