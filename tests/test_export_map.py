"""Maps back out (``output/rosmap.py``, ``mresim export-map``): a run's maps written as ROS
map_server maps read back cell for cell, with the run's resolution and its ROS map's
origin; a wrong map name or step names what the run has."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from mresim_phys.cli import main
from mresim_phys.output.rosmap import export_map, map_at, read_ros_belief, write_ros_map
from mresim_phys.output.runlog import RunLog
from mresim_phys.scenario.readers import load_ros_map
from mresim_phys.types import FREE, OCCUPIED, UNKNOWN

ROOT = Path(__file__).resolve().parent.parent


def test_a_grid_survives_the_round_trip(tmp_path: Path) -> None:
    rng = np.random.default_rng(0)
    grid = rng.choice(np.array([UNKNOWN, FREE, OCCUPIED], dtype=np.uint8), size=(37, 53))
    meta, pgm = write_ros_map(grid, tmp_path / "m", 0.05, (-1.5, 2.0, 0.0))
    assert pgm.is_file()
    assert np.array_equal(read_ros_belief(meta), grid)
    data = yaml.safe_load(meta.read_text())
    assert data["resolution"] == 0.05 and data["origin"] == [-1.5, 2.0, 0.0]
    assert data["mode"] == "trinary" and data["image"] == "m.pgm"


@pytest.fixture(scope="module")
def warehouse_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The ROS warehouse scenario, 40 steps."""
    folder = tmp_path_factory.mktemp("warehouse")
    data = yaml.safe_load((ROOT / "scenarios" / "05_warehouse_ros.yaml").read_text())
    data["map"]["ros"] = str(ROOT / "maps" / "warehouse.yaml")
    data["steps"] = 40
    scenario = folder / "scenario.yaml"
    scenario.write_text(yaml.safe_dump(data))
    out = folder / "run"
    assert main(["run", str(scenario), "--out", str(out), "--quiet", "--no-plots"]) == 0
    return out


def test_a_robots_map_and_the_truth_read_back_as_the_run_had_them(warehouse_run: Path) -> None:
    log = RunLog.open(warehouse_run / "log")
    meta, _ = export_map(warehouse_run, "A", 25, None)
    assert meta == warehouse_run / "maps" / "A-step00025.yaml"
    belief, _ = map_at(log, "A", 25)
    assert np.array_equal(read_ros_belief(meta), belief)
    assert (belief == UNKNOWN).any() and (belief == FREE).any()
    assert (
        main(
            ["export-map", str(warehouse_run), "--map", "truth", "--out", str(warehouse_run / "x")]
        )
        == 0
    )
    truth = load_ros_map(warehouse_run / "x" / "truth-step00040.yaml")  # the project's reader
    assert np.array_equal(truth.occupied, log.truth)
    original = load_ros_map(ROOT / "maps" / "warehouse.yaml")
    assert truth.resolution == original.resolution and truth.origin == original.origin


@pytest.mark.parametrize(
    ("flags", "message"),
    [(["--map", "Z"], "no map 'Z' in this run; give a robot"), (["--step", "999"], "not logged")],
)
def test_a_wrong_map_or_step_is_named(
    warehouse_run: Path, flags: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["export-map", str(warehouse_run), *flags]) == 2
    assert message in capsys.readouterr().err
