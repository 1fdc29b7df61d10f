"""Scenarios in metres and seconds on a ROS map: placed as RViz places them, run exactly as
the same scenario in cells, reported in metres and seconds; every mix-up is one paragraph
and exit status 2."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from test_runlog import assert_same_snapshot, record_run

from mresim_phys.cli import main
from mresim_phys.output.runlog import RunLog
from mresim_phys.render.scale_bar import draw_scale_bar, round_length
from mresim_phys.render.style import Style
from mresim_phys.scenario.frame import MapFrame
from mresim_phys.scenario.load import load_scenario
from mresim_phys.scenario.readers import load_map

REPO = Path(__file__).resolve().parent.parent
WAREHOUSE = REPO / "maps" / "warehouse.yaml"  # 300 x 200 cells of 0.05 m, origin (-7.5, -5)
IN_CELLS = REPO / "scenarios" / "05_warehouse_ros.yaml"


def in_metres(**changes: Any) -> dict[str, Any]:
    """Scenario 05 (the warehouse ROS map) written in metres and seconds, dt 0.1 s."""
    data: dict[str, Any] = {
        "name": "warehouse-metres",
        "seed": 11,
        "steps": 30,
        "units": "m",
        "dt": 0.1,
        "stop": {"explored": 0.95},
        "map": {"ros": str(WAREHOUSE)},
        "base_station": {"position": [5.5, 0.0], "comm_range": 3.0},
        "team": {"speed": 1.5, "radius": 0.1, "sensor": {"range": 4.0}, "comm_range": 3.0},
        "robots": [
            {"name": "A", "start": [4.75, 2.0]},
            {"name": "B", "start": [5.25, 2.0]},
            {"name": "C", "start": [5.75, 2.0]},
            {
                "name": "R",
                "start": [6.25, 2.0],
                "strategy": {"name": "random_walk", "params": {"distance": 40}},
            },
        ],
    }
    return {**data, **changes}


def write(folder: Path, data: dict[str, Any], name: str = "scenario.yaml") -> Path:
    path = folder / name
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return path


def test_a_map_frame_point_lands_in_the_pixel_rviz_draws_there() -> None:
    """RViz draws PGM pixel (column c, row r from the top) as the square from
    origin + (c, H - 1 - r) * resolution, one resolution wide: any point inside it is that
    cell, and the cell's centre maps back to the square's centre."""
    loaded = load_map(WAREHOUSE)
    rows, cols = loaded.occupied.shape
    assert loaded.origin is not None and loaded.resolution == 0.05
    frame = MapFrame(rows, cols, 0.05, loaded.origin[:2])
    rng = np.random.default_rng(0)
    for c, r in zip(rng.integers(0, cols, 200), rng.integers(0, rows, 200), strict=True):
        left = loaded.origin[0] + c * 0.05
        bottom = loaded.origin[1] + (rows - 1 - r) * 0.05
        u, v = rng.uniform(0.01, 0.99, 2)
        x, y = frame.to_cell(left + u * 0.05, bottom + v * 0.05)
        assert (math.floor(x), math.floor(y)) == (c, r)
        centre = frame.to_map(c + 0.5, r + 0.5)
        assert centre == pytest.approx((left + 0.025, bottom + 0.025), abs=1e-12)


def test_a_scenario_in_metres_is_the_same_scenario_in_cells(tmp_path: Path) -> None:
    metres = load_scenario(write(tmp_path, in_metres()))
    cells = load_scenario(IN_CELLS)
    assert [r.start for r in metres.robots] == [r.start for r in cells.robots]
    assert metres.base_station.position == cells.base_station.position == (260, 100)
    for a, b in zip(metres.robots, cells.robots, strict=True):
        assert (a.speed, a.radius, a.comm_range, a.sensor.range) == (
            b.speed, b.radius, b.comm_range, b.sensor.range,
        )  # fmt: skip
    assert metres.units == "cells" and metres.dt == 0.1  # converted once, never again


def test_it_runs_exactly_as_in_cells_and_reports_metres_and_seconds(tmp_path: Path) -> None:
    metres_dir, cells_dir = tmp_path / "m", tmp_path / "c"
    path = write(tmp_path, in_metres(render={"final_png": False}))
    assert main(["run", str(path), "--out", str(metres_dir), "--quiet", "--no-plots"]) == 0
    flags = ["--steps", "30", "--out", str(cells_dir), "--quiet", "--no-plots"]
    assert main(["run", str(IN_CELLS), *flags]) == 0
    metrics = (metres_dir / "metrics.csv").read_bytes()
    assert metrics == (cells_dir / "metrics.csv").read_bytes()
    cells = json.loads((cells_dir / "summary.json").read_text())
    summary = json.loads((metres_dir / "summary.json").read_text())
    assert "physical" not in cells  # a scenario in cells writes what it always wrote
    block = summary["physical"]
    assert block["dt_s"] == 0.1 and block["duration_s"] == pytest.approx(summary["steps"] * 0.1)
    for key in ("explored", "known_at_base"):
        for level, step in summary[f"steps_to_{key}"].items():
            want = None if step is None else pytest.approx(step * 0.1)
            assert block[f"seconds_to_{key}"][level] == want
    assert block["total_distance_m"] == pytest.approx(summary["total_distance"] * 0.05)
    assert block["resolution_m"] == 0.05 and block["origin_m"] == [-7.5, -5.0]
    *_, snap = RunLog.open(metres_dir / "log").snapshots()
    assert snap.step == summary["steps"]
    for robot in snap.robots:
        x, y = -7.5 + robot.position[0] * 0.05, -5.0 + (200 - robot.position[1]) * 0.05
        pose = block["robots"][robot.name]["final_pose_m"]
        assert pose[:2] == pytest.approx([x, y], abs=1e-6)
        assert pose[2] == pytest.approx(-math.degrees(robot.heading), abs=1e-6)


def test_the_log_keeps_dt_and_replays_it(tmp_path: Path) -> None:
    path = write(tmp_path, in_metres())
    live, _, _ = record_run(path, tmp_path / "log", 6)
    assert live[-1].dt == 0.1 and live[-1].resolution == 0.05
    for got, want in zip(RunLog.open(tmp_path / "log").snapshots(), live, strict=True):
        assert_same_snapshot(got, want)


def test_obstacles_doors_and_regions_turn_with_the_frame(tmp_path: Path) -> None:
    data = in_metres(
        obstacles=[
            {
                "name": "cart",
                "shape": {"polygon": [[0, 0], [0.5, 0], [0, 0.25]]},
                "motion": {"waypoints": [[4.0, 1.0], [5.0, 1.0]], "speed": 0.5},
            }
        ],
        doors=[{"name": "d", "between": [[0.0, 0.0], [0.5, 0.0]], "thickness": 0.15}],
        faults={"hazards": [{"region": {"box": [4.0, -1.0, 5.0, 0.5]}, "probability": 0.1}]},
        terrain={"regions": [{"circle": [5.0, 1.0, 0.5], "factor": 0.5}]},
    )
    scenario = load_scenario(write(tmp_path, data))
    cart = scenario.obstacles[0]
    assert [tuple(p) for p in cart.shape.polygon] == [(0, 0), (10, 0), (0, -5)]  # y up -> down
    assert [tuple(p) for p in cart.motion.waypoints] == [(230, 80), (250, 80)]
    assert cart.motion.speed == 1.0  # 0.5 m/s x 0.1 s / 0.05 m
    door = scenario.doors[0]
    assert [tuple(p) for p in door.between] == [(150, 100), (160, 100)] and door.thickness == 3
    assert scenario.faults is not None
    assert tuple(scenario.faults.hazards[0].region.box) == (230, 90, 250, 120)  # corners sorted
    assert scenario.terrain is not None
    assert tuple(scenario.terrain.regions[0].circle) == (250, 80, 10)


@pytest.mark.parametrize(
    ("changes", "words"),
    [
        ({"dt": None}, ["needs the step duration", "'dt'"]),
        ({"dt": 0}, ["'dt' as a positive number", "found dt: 0"]),
        ({"units": "metres"}, ["units", "'cells' or 'm'"]),
        ({"map": {"image": str(REPO / "maps" / "office.png")}}, ["'resolution'", "map.image"]),
        ({"robots": [{"name": "A", "start": [245, 60]}]}, ["robots[0].start", "off the map",
                                                           "check the map's origin"]),
        ({"base_station": {"position": [-9, 0]}}, ["base_station.position", "x -7.5 to 7.5 m"]),
    ],
)  # fmt: skip
def test_each_units_mistake_is_one_paragraph_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], changes: dict[str, Any], words: list[str]
) -> None:
    data = {k: v for k, v in in_metres(**changes).items() if v is not None}
    path = write(tmp_path, data)
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and str(path) in err
    assert all(w in err for w in words), err


def test_a_rotated_map_origin_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    meta = yaml.safe_load(WAREHOUSE.read_text())
    meta |= {"image": str(WAREHOUSE.parent / meta["image"]), "origin": [-7.5, -5.0, 0.3]}
    ros = write(tmp_path, meta, "rotated.yaml")
    path = write(tmp_path, in_metres(map={"ros": str(ros)}))
    assert main(["validate", str(path)]) == 2
    assert "rotated origin (yaw 0.3 rad)" in capsys.readouterr().err


def test_the_scale_bar_is_as_long_as_its_label_says() -> None:
    image = np.full((200, 600, 3), 128, np.uint8)
    px_per_cell, resolution = 2.0, 0.05  # 600 px = 300 cells = 15 m; a fifth: 3 m -> 2 m
    assert round_length(600 / 5 / px_per_cell * resolution) == 2.0
    draw_scale_bar(image, (600, 200), px_per_cell, resolution, Style())
    bar_row = image[200 - 8 - 1]
    black = np.flatnonzero((bar_row == 0).all(axis=1))
    assert black.max() - black.min() == round(2.0 / resolution * px_per_cell)


def test_validate_scenario_turns_a_mapping_in_metres_into_cells() -> None:
    """The public entry for scenarios given as data converts too: metres never pass for
    cells because a scenario came as a mapping rather than a file."""
    from mresim_phys.scenario.load import validate_scenario

    scenario = validate_scenario(in_metres(), "<data>")
    assert scenario.robots[0].start == (245.0, 60.0)
    assert scenario.units == "cells" and scenario.team.speed == 3.0


def test_a_beam_models_lengths_are_metres_and_its_rate_per_metre(tmp_path: Path) -> None:
    """With 'units: m' a sensor's beam block gives sigma_hit, max_free and speckle in
    metres and lambda_short per metre; the run holds them in cells (0.05 m a cell)."""
    beam = {"sigma_hit": 0.02, "max_free": 1.5, "speckle": 0.1, "lambda_short": 2.0}
    team = {"speed": 1.5, "radius": 0.1, "sensor": {"range": 4.0, "beam": beam}}
    scenario = load_scenario(write(tmp_path, in_metres(team=team)))
    got = scenario.robots[0].sensor.beam
    assert got is not None
    assert got.sigma_hit == pytest.approx(0.4) and got.max_free == pytest.approx(30.0)
    assert got.speckle == pytest.approx(2.0) and got.lambda_short == pytest.approx(0.1)
