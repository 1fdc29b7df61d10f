"""Sweeps on a job array (``sweeps/shards.py``): three shards run at once into one sweep
folder, every run exactly once; compare reads their union (a shard whose runs all failed
included) and names a missing shard; a SLURM array task finds its shard in its environment."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
import yaml

from mresim_phys.errors import MresimError
from mresim_phys.sweeps.expand import expand_runs
from mresim_phys.sweeps.shards import parse_shard, shard_from_env, slice_of
from mresim_phys.sweeps.study import load_study
from mresim_phys.sweeps.sweep_input import read_sweep

ROOT = Path(__file__).resolve().parent.parent


def study_file(tmp_path: Path) -> Path:
    data = {
        "name": "shards",
        "scenarios": [str(ROOT / "scenarios" / "01_quickstart.yaml")],
        "axes": {"team.strategy": ["frontier", "nearest_frontier"]},
        "seeds": 4,
        "steps": 25,
    }
    path = tmp_path / "study.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_three_shards_at_once_run_every_run_exactly_once(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    study = study_file(tmp_path)
    out = tmp_path / "out"
    command = [sys.executable, "-m", "mresim_phys.cli", "sweep", str(study), "--out", str(out)]
    jobs = [
        subprocess.Popen([*command, "--shard", f"{i}/3", "--workers", "1", "--quiet"])
        for i in range(3)
    ]
    assert [job.wait(timeout=600) for job in jobs] == [0, 0, 0]
    expected = [r.run_id for r in expand_runs(load_study(study), study)]
    sweep = read_sweep(out)
    assert sorted(sweep.runs["run_id"]) == sorted(expected)  # each once: no duplicates
    assert (sweep.runs["status"] == "done").all()
    assert set(sweep.steps["run_id"]) == set(expected)
    for i in range(3):
        shard = read_sweep(out / "shards" / f"{i}-of-3")
        assert list(shard.runs["run_id"]) == slice_of(expected, i, 3)
    (out / "shards" / "1-of-3" / "runs.parquet").unlink()  # as if shard 1 had not finished
    assert len(read_sweep(out).runs) == len(expected) - len(slice_of(expected, 1, 3))
    assert "shards 1-of-3 have not finished" in capsys.readouterr().err
    table = out / "shards" / "0-of-3" / "runs.parquet"
    runs = pd.read_parquet(table)
    runs["status"] = "failed"  # as if every run of shard 0 had failed: the others compare
    runs.to_parquet(table)
    union = read_sweep(out).runs
    assert set(union.loc[union["status"] == "failed", "run_id"]) == set(slice_of(expected, 0, 3))
    assert (union["status"] == "done").sum() == len(slice_of(expected, 2, 3))


def test_a_shard_is_i_of_n_from_the_flag_or_a_slurm_array_task() -> None:
    assert parse_shard("2/5") == (2, 5)
    for bad in ("5/5", "1", "-1/3", "a/b"):
        with pytest.raises(ValueError, match="shard"):
            parse_shard(bad)
    task = {"SLURM_ARRAY_TASK_ID": "4", "SLURM_ARRAY_TASK_MIN": "1", "SLURM_ARRAY_TASK_COUNT": "8"}
    assert shard_from_env(task) == (3, 8)
    assert shard_from_env({}) is None
    with pytest.raises(MresimError, match="SLURM_ARRAY_TASK_ID=9"):
        shard_from_env({"SLURM_ARRAY_TASK_ID": "9", "SLURM_ARRAY_TASK_COUNT": "8"})
