"""One sweep writes a sweep folder at a time: a second ``mresim sweep`` of the folder is
refused (exit 2, naming the holder), a lock left by a dead sweep is taken over."""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import threading
from pathlib import Path

import pytest
from conftest import write_study

from mresim_phys.cli import main
from mresim_phys.sweeps import lock as lock_module
from mresim_phys.sweeps.lifeline import Owner
from mresim_phys.sweeps.lock import SweepLock, SweepLocked

REPO = Path(__file__).resolve().parent.parent
QUICKSTART = REPO / "scenarios" / "01_quickstart.yaml"


def dead_pid() -> int:
    """The pid of a process that has ended."""
    process = subprocess.Popen([sys.executable, "-c", "pass"])
    process.wait()
    return process.pid


def test_a_folder_another_sweep_holds_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    study, out = write_study(tmp_path), tmp_path / "out"
    out.mkdir()
    with SweepLock(out):
        code = main(["sweep", str(study), "--out", str(out), "--workers", "1"])
        err = capsys.readouterr().err
    assert code == 2
    assert f"pid {os.getpid()} on host {socket.gethostname()}" in err
    assert str(out / "sweep.lock") in err and "Traceback" not in err
    assert sorted(p.name for p in out.iterdir()) == ["sweep.lock"]  # nothing written
    assert main(["sweep", str(study), "--out", str(out), "--workers", "1", "--quiet"]) == 0


def test_a_lock_left_by_a_dead_sweep_is_taken_over(tmp_path: Path) -> None:
    study, out = write_study(tmp_path, seeds=1), tmp_path / "out"
    out.mkdir()
    record = {"pid": dead_pid(), "host": socket.gethostname(), "started": 1, "since": 0}
    (out / "sweep.lock").write_text(json.dumps(record), encoding="utf-8")
    assert main(["sweep", str(study), "--out", str(out), "--workers", "1", "--quiet"]) == 0
    assert (out / "runs.parquet").is_file()


def test_without_flock_the_lock_file_is_created_exclusively(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(lock_module, "fcntl", None)
    with SweepLock(tmp_path) as held:
        assert json.loads(held.path.read_text(encoding="utf-8"))["pid"] == os.getpid()
        with pytest.raises(SweepLocked, match=f"pid {os.getpid()} on host"):
            SweepLock(tmp_path).acquire()
    assert not (tmp_path / "sweep.lock").exists()  # released
    record = {"pid": dead_pid(), "host": socket.gethostname()}
    (tmp_path / "sweep.lock").write_text(json.dumps(record), encoding="utf-8")
    with SweepLock(tmp_path):  # a dead owner's lock: stale, replaced
        pass
    record = {"pid": 1, "host": "another-machine"}
    (tmp_path / "sweep.lock").write_text(json.dumps(record), encoding="utf-8")
    with pytest.raises(SweepLocked, match="pid 1 on host another-machine"):
        SweepLock(tmp_path).acquire()  # another host's owner cannot be asked


@pytest.mark.slow
def test_two_sweeps_started_together_run_each_run_once(tmp_path: Path) -> None:
    """Two ``mresim sweep`` of one study into one folder at the same moment: one runs the
    sweep, the other is refused; the manifest has each run once."""
    study, out = write_study(tmp_path, seeds=3), tmp_path / "out"
    command = [sys.executable, "-m", "mresim_phys.cli", "sweep", str(study), "--out", str(out)]
    command += ["--workers", "1", "--quiet"]
    env = dict(os.environ, PYTHONPATH=str(REPO))
    both = [subprocess.Popen(command, env=env, stderr=subprocess.PIPE, text=True) for _ in "ab"]
    errors = [p.communicate(timeout=300)[1] for p in both]
    results = [(p.returncode, err) for p, err in zip(both, errors, strict=True)]
    assert sorted(code for code, _ in results) == [0, 2], results
    refused = next(err for code, err in results if code == 2)
    assert "is being written by another `mresim sweep`" in refused and "pid " in refused
    lines = (out / "manifest.jsonl").read_text(encoding="utf-8").splitlines()
    ids = [json.loads(line)["run_id"] for line in lines]
    assert sorted(ids) == ["a000-s0000", "a000-s0001", "a000-s0002"]


def test_a_sweep_that_is_beginning_is_named_too(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The holder is named even while its folder has no sweep.json yet (the folder would
    otherwise be refused as one that holds no sweep)."""
    study, out = write_study(tmp_path), tmp_path / "out"
    (out / "runs").mkdir(parents=True)
    with SweepLock(out):
        code = main(["sweep", str(study), "--out", str(out), "--workers", "1"])
    err = capsys.readouterr().err
    assert code == 2 and "is being written by another `mresim sweep`" in err


def test_a_sweep_that_has_just_taken_the_lock_is_named_once_it_writes_its_record(
    tmp_path: Path,
) -> None:
    """A sweep writes its record just after it flocks the file, and a flocked file keeps a
    former owner's record: one refused in between waits for the record that names the live
    holder instead of calling it unreadable (two sweeps started together, under load)."""
    fcntl = pytest.importorskip("fcntl")
    path = tmp_path / "sweep.lock"
    path.write_text(json.dumps({"pid": dead_pid(), "host": socket.gethostname()}))
    fd = os.open(path, os.O_RDWR)
    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)

    def write_record() -> None:
        data = json.dumps(Owner.me().to_json()).encode()
        os.pwrite(fd, data, 0)
        os.ftruncate(fd, len(data))

    late = threading.Timer(0.2, write_record)
    late.start()
    try:
        with pytest.raises(SweepLocked, match=f"pid {os.getpid()} on host"):
            SweepLock(tmp_path).acquire()
    finally:
        late.join()
        os.close(fd)
