"""Running sweeps: process pool and Dask give the same runs; failed runs; kill and resume."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pandas as pd
import pytest
import yaml

from mresim_phys.cli import main
from mresim_phys.output.replay import replay_run
from mresim_phys.sweeps.executors import DaskPool
from mresim_phys.sweeps.runner import SweepOptions, run_sweep
from mresim_phys.sweeps.study import load_study
from mresim_phys.sweeps.tables import WALL_COLUMNS

REPO = Path(__file__).resolve().parent.parent
QUICKSTART = REPO / "scenarios" / "01_quickstart.yaml"
AXES = {"team.strategy": ["frontier", "random_walk"], "team.comm_range": [20, 40]}


def write_study(folder: Path, **fields: Any) -> Path:
    """A study of the quickstart scenario (12 steps a run) written into ``folder``."""
    data = {"name": "t", "scenarios": [str(QUICKSTART)], "seeds": 3, "steps": 12, **fields}
    path = folder / "study.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return path


def tables(folder: Path) -> tuple[pd.DataFrame, pd.DataFrame]:
    """runs.parquet without its wall-clock columns, and steps.parquet."""
    runs = pd.read_parquet(folder / "runs.parquet")
    return runs.drop(columns=[c for c in WALL_COLUMNS if c in runs]), pd.read_parquet(
        folder / "steps.parquet"
    )


def test_pool_and_dask_give_the_same_runs(tmp_path: Path) -> None:
    """A 2x2x3 study on the process pool and on a dask.distributed LocalCluster."""
    study_path = write_study(tmp_path, axes=AXES)
    assert (
        main(
            ["sweep", str(study_path), "--out", str(tmp_path / "pool"), "--workers", "2", "--quiet"]
        )
        == 0
    )
    study, text = load_study(study_path), study_path.read_text(encoding="utf-8")
    from distributed import Client, LocalCluster

    # an in-process cluster (one worker thread): the runs go through Dask's scheduler and
    # serialisation while the test stays quick; it is closed at the end of the block
    with (
        LocalCluster(
            n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None
        ) as cluster,
        Client(cluster) as client,
    ):
        backend = DaskPool(client, own=False)
        options = SweepOptions(tmp_path / "dask", quiet=True, backend=backend)
        result = run_sweep(study, study_path, text, options)
    assert result.ran == 12 and not result.failed and "Dask" in result.backend
    pool_runs, pool_steps = tables(tmp_path / "pool")
    dask_runs, dask_steps = tables(tmp_path / "dask")
    assert len(pool_runs) == 12 and set(pool_runs["status"]) == {"done"}
    assert list(pool_runs["team.comm_range"][:6]) == [20, 20, 20, 40, 40, 40]
    pd.testing.assert_frame_equal(pool_runs, dask_runs)
    pd.testing.assert_frame_equal(pool_steps, dask_steps)
    assert len(pool_steps) == pool_runs["steps"].add(1).sum()
    assert pool_runs["final_explored"].nunique() > 1  # the arms and seeds really differ
    replayed = replay_run(tmp_path / "pool" / "runs" / "a003-s0002", {}, metrics=True)
    assert replayed.ok  # every run folder is a normal run folder


def test_a_failing_run_is_recorded_and_the_sweep_goes_on(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    strategies = ["random_walk", "sweep_plugins:Breaks"]  # tests/sweep_plugins.py
    study = write_study(tmp_path, axes={"team.strategy": strategies}, seeds=2)
    out = tmp_path / "out"
    video_for = "seed == 1 and strategy == 'random_walk'"
    code = main(
        [
            "sweep",
            str(study),
            "--out",
            str(out),
            "--workers",
            "2",
            "--quiet",
            "--video-for",
            video_for,
        ]
    )
    assert code == 1
    assert [p.name for p in (out / "videos").iterdir()] == ["a000-s0001.mp4"]
    assert (out / "videos" / "a000-s0001.mp4").stat().st_size > 1000
    runs = pd.read_parquet(out / "runs.parquet").set_index("run_id")
    assert list(runs["status"]) == ["done", "done", "failed", "failed"]
    failed = runs.loc["a001-s0000"]
    assert "RuntimeError: this strategy has a bug" in failed["error"]
    log = Path(failed["log"])
    assert log.parent == out / "errors" and "Traceback" in log.read_text(encoding="utf-8")
    assert not (out / "runs" / "a001-s0000").exists()
    assert sorted(p.name for p in (out / "runs").iterdir()) == ["a000-s0000", "a000-s0001"]
    assert main(["sweep", str(study), "--out", str(out), "--workers", "1"]) == 1
    summary = capsys.readouterr().out
    assert "2 done, 2 failed, 0 lost (ran 0 now" in summary and str(log) in summary
    assert main(["compare", str(out), "--metric", "final_explored"]) == 0
    report = (out / "compare" / "report.md").read_text(encoding="utf-8")
    failed_part = report.split("## Failed and lost runs", 1)[1]
    assert "a001-s0000" in failed_part and "a001-s0001" in failed_part
    assert (
        "| strategy=random_walk | 2 | " in report
        and "| strategy=sweep_plugins:Breaks | 0 | - | - | [-, -] | 2 |" in report
    )


def manifest_lines(out: Path) -> list[dict[str, Any]]:
    """The manifest's complete lines."""
    path = out / "manifest.jsonl"
    if not path.is_file():
        return []
    return [json.loads(x) for x in path.read_text(encoding="utf-8").splitlines() if x.strip()]


def test_a_killed_sweep_resumes_without_losing_or_repeating_runs(tmp_path: Path) -> None:
    study = write_study(tmp_path, axes=AXES, steps=25)
    out = tmp_path / "out"
    command = [
        sys.executable,
        "-m",
        "mresim_phys.cli",
        "sweep",
        str(study),
        "--out",
        str(out),
        "--workers",
        "2",
        "--quiet",
    ]
    env = dict(os.environ, PYTHONPATH=str(REPO))
    process = subprocess.Popen(command, env=env, start_new_session=True)
    try:
        deadline = time.monotonic() + 60
        while len(manifest_lines(out)) < 3 and process.poll() is None:
            assert time.monotonic() < deadline, "the sweep made no progress"
            time.sleep(0.05)
    finally:
        os.killpg(process.pid, signal.SIGKILL)  # the sweep and its workers
        process.wait()
    first = [r["run_id"] for r in manifest_lines(out)]
    before = set(first)
    assert 3 <= len(before) < 12, "kill the sweep mid-way"
    stamps = {r: (out / "runs" / r / "summary.json").stat().st_mtime_ns for r in before}
    assert not (out / "runs.parquet").exists()
    resumed = subprocess.run(command, env=env, capture_output=True, text=True, timeout=120)
    assert resumed.returncode == 0, resumed.stderr
    again = [r["run_id"] for r in manifest_lines(out)]
    assert again[: len(first)] == first and not set(again[len(first) :]) & before
    assert len(again) == len(set(again)) == 12  # each run once: none lost, none repeated
    runs = pd.read_parquet(out / "runs.parquet")
    assert sorted(runs["run_id"]) == sorted(set(again)) and set(runs["status"]) == {"done"}
    folders = sorted(p.name for p in (out / "runs").iterdir())
    assert folders == sorted(runs["run_id"])  # no temporary folder left
    assert stamps == {r: (out / "runs" / r / "summary.json").stat().st_mtime_ns for r in before}


def test_more_seeds_carry_on_and_changed_runs_are_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    args = ["sweep", str(tmp_path / "study.yaml"), "--out", str(out), "--workers", "1"]
    write_study(tmp_path, seeds=1, steps=5)
    assert main(args) == 0
    write_study(tmp_path, seeds=2, steps=5)
    assert main(args) == 0
    assert "2 runs, 2 done, 0 failed, 0 lost (ran 1 now" in capsys.readouterr().out
    assert len(pd.read_parquet(out / "runs.parquet")) == 2
    write_study(tmp_path, seeds=2, steps=6)
    assert main(args) == 2
    assert (
        "whose runs ['a000-s0000', 'a000-s0001'] had other scenario data" in capsys.readouterr().err
    )


@pytest.mark.slow
def test_dask_local_cluster_of_processes_from_the_command_line(tmp_path: Path) -> None:
    """``--dask local:2`` starts (and stops) a LocalCluster of worker processes."""
    study = write_study(tmp_path, axes={"team.strategy": ["frontier", "random_walk"]}, seeds=2)
    for out, flag in (("dask", ["--dask", "local:2"]), ("pool", ["--workers", "2"])):
        assert main(["sweep", str(study), "--out", str(tmp_path / out), "--quiet", *flag]) == 0
    pd.testing.assert_frame_equal(tables(tmp_path / "dask")[0], tables(tmp_path / "pool")[0])
    pd.testing.assert_frame_equal(tables(tmp_path / "dask")[1], tables(tmp_path / "pool")[1])


def test_video_for_a_minus_before_a_string_axis_is_a_clear_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    study = write_study(tmp_path, axes={"team.strategy": ["frontier", "random_walk"]})
    out = tmp_path / "out"
    code = main(["sweep", str(study), "--out", str(out), "--video-for", "-strategy == 1"])
    err = capsys.readouterr().err
    assert code == 2 and "--video-for '-strategy == 1'" in err and "not a number" in err
    assert "Traceback" not in err and err.count("\n") == 1 and not out.exists()
