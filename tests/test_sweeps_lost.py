"""Lost runs: a run failed by the machine (a dead worker, a full disk, a lost Dask
connection) is told from a run's own error and run again on resume; ``--retry-failed``
runs the failed ones again too."""

from __future__ import annotations

import errno
import json
from concurrent.futures import Future
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path
from typing import Any

import pandas as pd
import pytest
from conftest import write_study

from mresim_phys.cli import main
from mresim_phys.output.files import WriteError
from mresim_phys.sweeps import worker
from mresim_phys.sweeps.executors import BackendLost
from mresim_phys.sweeps.expand import RunSpec
from mresim_phys.sweeps.runner import SweepOptions, run_sweep
from mresim_phys.sweeps.study import load_study

REPO = Path(__file__).resolve().parent.parent
QUICKSTART = REPO / "scenarios" / "01_quickstart.yaml"


def manifest_lines(out: Path) -> list[dict[str, Any]]:
    """Every line of the manifest."""
    text = (out / "manifest.jsonl").read_text(encoding="utf-8")
    return [json.loads(line) for line in text.splitlines()]


class InProcess:
    """A backend running each run in this process, except the runs in ``lose``, whose
    futures fail as a dead worker's do; ``fatal`` makes recover() give up (a Dask client
    that lost its scheduler)."""

    slots, name = 1, "in-process test backend"

    def __init__(self, lose: set[str], error: BaseException, fatal: bool = False) -> None:
        self.lose, self.error, self.fatal = lose, error, fatal
        self.lost_workers, self.recovered = 0, 0

    def submit(self, spec: RunSpec, sweep: str) -> Any:
        future: Future[dict[str, Any]] = Future()
        if spec.run_id in self.lose:
            future.set_exception(self.error)
        else:
            future.set_result(worker.run_task(spec, sweep))
        return future

    def wait_any(self, futures: list[Any]) -> list[Any]:
        return futures

    def recover(self, lost: int) -> None:
        self.lost_workers += lost
        self.recovered += 1
        if self.fatal:
            raise BackendLost("lost the Dask scheduler at tcp://test:1")

    def close(self) -> None:
        pass


def sweep_in_process(study: Path, out: Path, backend: InProcess, retry: bool = False) -> Any:
    """run_sweep of ``study`` into ``out`` on ``backend``."""
    options = SweepOptions(out, quiet=True, backend=backend, retry_failed=retry)
    return run_sweep(load_study(study), study, study.read_text(encoding="utf-8"), options)


def test_a_full_disk_is_lost_and_a_bug_is_failed(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    spec = next(iter(load_study_runs(write_study(tmp_path))))

    def full(spec: RunSpec, sweep: Path) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(worker, "simulate", full)
    record = worker.run_task(spec, str(tmp_path / "out"))
    assert record["status"] == "lost" and "No space left" in record["error"]
    assert not (tmp_path / "out" / "inflight" / f"{spec.run_id}.json").exists()

    def written(spec: RunSpec, sweep: Path) -> None:
        raise WriteError(sweep / "metrics.csv", "No space left on device")

    monkeypatch.setattr(worker, "simulate", written)
    record = worker.run_task(spec, str(tmp_path / "out"))
    assert record["status"] == "lost" and "cannot write" in record["error"]

    def bug(spec: RunSpec, sweep: Path) -> None:
        raise ZeroDivisionError("a strategy's bug")

    monkeypatch.setattr(worker, "simulate", bug)
    record = worker.run_task(spec, str(tmp_path / "out"))
    assert record["status"] == "failed" and "ZeroDivisionError" in record["error"]
    assert "Traceback" in Path(record["log"]).read_text(encoding="utf-8")


def load_study_runs(path: Path) -> list[RunSpec]:
    """The runs of the study file ``path``."""
    from mresim_phys.sweeps.expand import expand_runs

    return expand_runs(load_study(path), path)


def test_runs_of_a_dead_worker_are_lost_and_run_again_on_resume(tmp_path: Path) -> None:
    study, out = write_study(tmp_path), tmp_path / "out"
    backend = InProcess({"a000-s0001"}, BrokenProcessPool("a worker died"))
    result = sweep_in_process(study, out, backend)
    assert [r["run_id"] for r in result.lost] == ["a000-s0001"] and not result.complete
    assert backend.recovered == 1 and result.lost_workers == 1
    summary = result.summary()
    assert "1 done, 0 failed, 1 lost" in summary and "lost 1 worker(s)" in summary
    assert "BrokenProcessPool" in summary and "run the same command again" in summary
    runs = pd.read_parquet(out / "runs.parquet").set_index("run_id")
    assert list(runs["status"]) == ["done", "lost"]
    again = sweep_in_process(study, out, InProcess(set(), RuntimeError()))
    assert again.complete and again.ran == 1 and again.reran == 1
    assert "re-ran 1" in again.summary()
    lines = manifest_lines(out)
    assert [(x["run_id"], x["status"], x["attempt"]) for x in lines] == [
        ("a000-s0000", "done", 1),
        ("a000-s0001", "lost", 1),
        ("a000-s0001", "done", 2),
    ]
    runs = pd.read_parquet(out / "runs.parquet").set_index("run_id")
    assert list(runs["status"]) == ["done", "done"] and list(runs["attempt"]) == [1, 2]


def test_a_lost_dask_scheduler_stops_the_sweep_and_keeps_what_finished(tmp_path: Path) -> None:
    study, out = write_study(tmp_path, seeds=3), tmp_path / "out"
    backend = InProcess({"a000-s0001"}, OSError("CommClosedError"), fatal=True)
    result = sweep_in_process(study, out, backend)
    assert result.stopped is not None and "tcp://test:1" in result.stopped
    assert result.ran == 2 and not result.complete  # the third run was never started
    assert [x["status"] for x in manifest_lines(out)] == ["done", "lost"]
    assert "stopped: lost the Dask scheduler" in result.summary()
    assert len(pd.read_parquet(out / "runs.parquet")) == 2  # the tables of what finished
    again = sweep_in_process(study, out, InProcess(set(), RuntimeError()))
    assert again.complete and again.ran == 2


def test_a_killed_worker_process_loses_its_runs_and_the_sweep_goes_on(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A real worker process SIGKILLed mid-run (sweep_crash_plugins.Dies): its run is lost
    (not failed), the pool is replaced, the other runs finish; a resume runs the lost run
    again; ``--retry-failed`` runs the failed ones (of their own error) again."""
    strategies = ["random_walk", "sweep_crash_plugins:Dies", "sweep_plugins:Breaks"]
    study = write_study(tmp_path, axes={"team.strategy": strategies}, seeds=1)
    out = tmp_path / "out"
    args = ["sweep", str(study), "--out", str(out), "--workers", "1"]
    assert main(args) == 1
    text = capsys.readouterr().out
    assert "1 done, 1 failed, 1 lost" in text and "lost 1 worker(s)" in text
    status = {x["run_id"]: x["status"] for x in manifest_lines(out)}
    assert status == {"a000-s0000": "done", "a001-s0000": "lost", "a002-s0000": "failed"}
    assert main(args) == 1
    text = capsys.readouterr().out
    assert "(ran 1 now on 1 local process; re-ran 1)" in text  # only the lost run
    assert main([*args, "--retry-failed"]) == 1
    assert "(ran 2 now on 1 local process; re-ran 2)" in capsys.readouterr().out
    attempts = [(x["run_id"], x["attempt"]) for x in manifest_lines(out)]
    assert attempts[3:] == [("a001-s0000", 2), ("a001-s0000", 3), ("a002-s0000", 2)]
    assert not list((out / "runs").glob("*.tmp-*"))  # the dead worker's folder went
    assert main(["compare", str(out), "--metric", "final_explored"]) == 0
    report = (out / "compare" / "report.md").read_text(encoding="utf-8")
    assert "3 runs, 1 done, 1 failed, 1 lost (2 run again after a lost or failed attempt)" in report
    assert (
        "| a001-s0000 | quickstart: team.strategy=sweep_crash_plugins:Dies | 0 | lost |" in report
    )
    assert "BrokenProcessPool" in report


def test_lost_runs_run_again_and_failed_ones_only_when_asked(tmp_path: Path) -> None:
    from mresim_phys.sweeps.manifest import Manifest

    specs = load_study_runs(write_study(tmp_path, seeds=3))
    records = {
        "a000-s0000": {"run_id": "a000-s0000", "status": "done"},
        "a000-s0001": {"run_id": "a000-s0001", "status": "failed"},
        "a000-s0002": {"run_id": "a000-s0002", "status": "lost"},
    }
    manifest = Manifest(tmp_path, records)
    assert [r.run_id for r in manifest.todo(specs)] == ["a000-s0002"]
    assert [r.run_id for r in manifest.todo(specs, retry_failed=True)] == [
        "a000-s0001",
        "a000-s0002",
    ]
