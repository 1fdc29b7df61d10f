"""``mresim compare`` on a partial or damaged sweep folder: every case is a correct report or
one message naming the file and the column (exit status 2), never a traceback."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pandas as pd
import pytest
import yaml

from mresim_phys.cli import main

REPO = Path(__file__).resolve().parent.parent
QUICKSTART = REPO / "scenarios" / "01_quickstart.yaml"
RUNS_COLUMNS = [
    "run_id", "arm", "label", "scenario", "team.strategy", "failures", "seed", "status",
    "error", "log", "run_time_s", "attempt", "steps", "stop_reason", "wall_time_s",
    "steps_per_second", "final_explored", "final_known_at_base", "steps_to_explored_50",
    "steps_to_explored_90", "steps_to_explored_95", "steps_to_known_at_base_50",
    "steps_to_known_at_base_90", "steps_to_known_at_base_95", "total_distance", "alive",
    "comm_bytes", "control_bytes", "mean_links", "latency_max", "latency_mean",
    "auc_explored", "auc_known_at_base", "alive_fraction", "base_deficit_at_end",
    "base_deficit_fraction_at_end", "failed_robots", "robots_idle_with_frontier",
    "idle_robot_steps", "stuck_robot_steps", "waiting_robot_steps", "robots_fruitless",
    "fruitless_robot_steps", "explorable_cells",
    "connected_cells",
    "final_explored_connected", "final_known_at_base_connected",
    *(f"steps_to_{what}_connected_{level}" for what in ("explored", "known_at_base")
      for level in (50, 90, 95)),
]  # fmt: skip
STEPS_COLUMNS = [
    "run_id", "step", "explored", "known_at_base", "explored_connected",
    "known_at_base_connected", "distance", "alive", "links",
    "comm_bytes", "control_links", "control_bytes", "latency_max", "latency_mean",
    "distance_A", "distance_B", "state_A", "state_B", "base_contact_A", "base_contact_B",
]  # fmt: skip
TABLES = ("sweep.json", "runs.parquet", "steps.parquet")


@pytest.fixture(scope="module")
def sweep(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A finished sweep: random_walk and a strategy that always fails (failed runs in the
    report) x 0 or 1 robot failures (the degradation figure) x 2 seeds, 10 steps."""
    folder = tmp_path_factory.mktemp("sweep")
    data = {
        "name": "t",
        "scenarios": [str(QUICKSTART)],
        "seeds": 2,
        "steps": 10,
        "axes": {"team.strategy": ["random_walk", "sweep_plugins:Breaks"], "failures": [0, 1]},
    }
    (folder / "study.yaml").write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    args = ["sweep", str(folder / "study.yaml"), "--out", str(folder / "out"), "--quiet"]
    assert main([*args, "--workers", "2"]) == 1  # the Breaks runs fail
    return folder / "out"


def copy(sweep: Path, into: Path) -> Path:
    """The sweep's tables and record, copied into ``into``."""
    into.mkdir()
    for name in TABLES:
        shutil.copy(sweep / name, into / name)
    return into


def compare(folder: Path, capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    """``mresim compare folder``: exit status and stderr (a traceback fails the test)."""
    code = main(["compare", str(folder)])
    return code, capsys.readouterr().err


def assert_clear(code: int, err: str, *names: str) -> None:
    """Exit 2 with one paragraph naming each of ``names``."""
    assert code == 2, err
    assert err.startswith("mresim: error: ") and err.count("\n") == 1, err
    for name in names:
        assert name in err, (name, err)


def assert_reported(code: int, err: str, folder: Path) -> None:
    """Exit 0 with a report and the curves."""
    assert code == 0, err
    report = (folder / "compare" / "report.md").read_text(encoding="utf-8")
    assert "8 runs, 4 done, 4 failed, 0 lost" in report
    assert (folder / "compare" / "curves.png").stat().st_size > 1000


def test_the_cases_cover_every_column(sweep: Path) -> None:
    assert set(pd.read_parquet(sweep / "runs.parquet").columns) == set(RUNS_COLUMNS)
    assert set(pd.read_parquet(sweep / "steps.parquet").columns) == set(STEPS_COLUMNS)


@pytest.mark.parametrize(
    ("table", "column"),
    [("runs.parquet", c) for c in RUNS_COLUMNS] + [("steps.parquet", c) for c in STEPS_COLUMNS],
)
def test_a_table_without_a_column(
    table: str, column: str, sweep: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = copy(sweep, tmp_path / "s")
    pd.read_parquet(folder / table).drop(columns=[column]).to_parquet(folder / table)
    code, err = compare(folder, capsys)
    if code == 0:
        assert_reported(code, err, folder)
    else:
        assert_clear(code, err, str(folder / table), repr(column))


@pytest.mark.parametrize(
    ("record", "says"),
    [
        ([], "the sweep record is list, not a JSON object"),
        (None, "the sweep record is NoneType, not a JSON object"),
        ("t", "the sweep record is str, not a JSON object"),
        ({"study": "t", "axes": "failures"}, "field 'axes' is 'failures'"),
        ({"study": "t", "axes": [1]}, "field 'axes' is [1]"),
        ({"study": "t", "axes": ["robots.count"]}, "column 'robots.count' is missing"),
        ({"study": "t", "axes": [], "reference": [0]}, "field 'reference' is [0]"),
        ({"study": 3, "axes": []}, "field 'study' is 3"),
    ],
)
def test_a_damaged_sweep_record(
    record: object, says: str, sweep: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = copy(sweep, tmp_path / "s")
    (folder / "sweep.json").write_text(json.dumps(record), encoding="utf-8")
    code, err = compare(folder, capsys)
    assert_clear(code, err, "sweep.json" if "column" not in says else "runs.parquet", says)


def test_a_record_without_axes_compares_by_scenario(
    sweep: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = copy(sweep, tmp_path / "s")
    (folder / "sweep.json").write_text("{}", encoding="utf-8")
    assert_reported(*compare(folder, capsys), folder)


def test_damaged_tables(sweep: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = copy(sweep, tmp_path / "text")
    steps = pd.read_parquet(folder / "steps.parquet")
    steps.assign(step=steps["step"].astype(str)).to_parquet(folder / "steps.parquet")
    assert_clear(*compare(folder, capsys), "steps.parquet", "column 'step' holds str, not numbers")
    folder = copy(sweep, tmp_path / "twice")
    pd.concat([steps, steps.iloc[:1]]).to_parquet(folder / "steps.parquet")
    assert_clear(*compare(folder, capsys), "steps.parquet", "'run_id', 'step' hold")
    folder = copy(sweep, tmp_path / "garbage")
    (folder / "runs.parquet").write_bytes(b"not parquet")
    assert_clear(*compare(folder, capsys), "runs.parquet", "cannot read the table")
    folder = copy(sweep, tmp_path / "empty")
    pd.read_parquet(folder / "runs.parquet").iloc[:0].to_parquet(folder / "runs.parquet")
    assert_clear(*compare(folder, capsys), "no run of the sweep finished")
    folder = copy(sweep, tmp_path / "ids")
    runs = pd.read_parquet(folder / "runs.parquet")
    pd.concat([runs, runs.iloc[:1]]).to_parquet(folder / "runs.parquet")
    assert_clear(*compare(folder, capsys), "runs.parquet", "column 'run_id' holds 'a000-s0000'")
    folder = copy(sweep, tmp_path / "metrics")
    metrics = [c for c in runs.columns if c.startswith(("steps_to_", "auc_", "final_"))]
    metrics += [
        "robots_idle_with_frontier",
        "idle_robot_steps",
        "stuck_robot_steps",
        "waiting_robot_steps",
        "robots_fruitless",
        "fruitless_robot_steps",
    ]
    runs.drop(columns=metrics).to_parquet(folder / "runs.parquet")
    assert_clear(*compare(folder, capsys), "runs.parquet", "none of the default metrics")
