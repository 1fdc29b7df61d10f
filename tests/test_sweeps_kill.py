"""A SIGKILLed ``mresim sweep`` takes its workers with it, and a resume never deletes a run
folder a live process writes (it waits for that process), then finishes the sweep."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
import yaml

from mresim_phys.sweeps.inflight import wait_for_writers, writers
from mresim_phys.sweeps.lifeline import Owner, start_time, this_host
from mresim_phys.sweeps.manifest import clean_leftovers

REPO = Path(__file__).resolve().parent.parent
QUICKSTART = REPO / "scenarios" / "01_quickstart.yaml"
linux = pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs /proc")


def session_members(sid: int) -> list[int]:
    """The live (not zombie) processes of session ``sid``."""
    members = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text(encoding="ascii").rsplit(")", 1)[1].split()
        except (OSError, IndexError):
            continue
        if int(fields[3]) == sid and fields[0] not in "ZX":
            members.append(int(stat.parent.name))
    return members


def write_marker(sweep: Path, run_id: str, owner: Owner) -> Path:
    """An in-flight marker of ``run_id`` naming ``owner``."""
    path = sweep / "inflight" / f"{run_id}.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(owner.to_json()), encoding="utf-8")
    return path


@linux
def test_workers_die_with_a_killed_sweep_and_a_resume_finishes_it(tmp_path: Path) -> None:
    data = {
        "name": "t",
        "scenarios": [str(QUICKSTART)],
        "seeds": 3,
        "steps": 60,
        "axes": {"team.strategy": ["frontier", "random_walk"]},
    }
    study, out = tmp_path / "study.yaml", tmp_path / "out"
    study.write_text(yaml.safe_dump(data), encoding="utf-8")
    command = [sys.executable, "-m", "mresim_phys.cli", "sweep", str(study), "--out", str(out)]
    command += ["--workers", "2", "--quiet"]
    env = dict(os.environ, PYTHONPATH=str(REPO))
    process = subprocess.Popen(command, env=env, start_new_session=True)
    try:
        deadline = time.monotonic() + 120
        while len(list((out / "inflight").glob("*.json"))) < 2:  # both workers mid-run
            assert process.poll() is None and time.monotonic() < deadline, "no runs started"
            time.sleep(0.05)
        os.kill(process.pid, signal.SIGKILL)  # the sweep alone, not its process group
        process.wait()
        deadline = time.monotonic() + 5
        while session_members(process.pid) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert session_members(process.pid) == []  # workers, forkserver, resource tracker
    finally:
        for pid in session_members(process.pid):
            os.kill(pid, signal.SIGKILL)
    resumed = subprocess.run(command, env=env, capture_output=True, text=True, timeout=300)
    assert resumed.returncode == 0, resumed.stderr
    lines = (out / "manifest.jsonl").read_text(encoding="utf-8").splitlines()
    records = [json.loads(line) for line in lines]
    assert sorted(r["run_id"] for r in records) == sorted(
        f"a00{a}-s000{s}" for a in range(2) for s in range(3)
    )  # each run once: none lost, none repeated
    assert {r["status"] for r in records} == {"done"}
    assert sorted(p.name for p in (out / "runs").iterdir()) == sorted(r["run_id"] for r in records)
    assert list((out / "inflight").iterdir()) == []


@linux
def test_a_resume_keeps_and_waits_for_folders_a_live_process_writes(tmp_path: Path) -> None:
    (tmp_path / "runs").mkdir()
    writer = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        live = Owner(writer.pid, this_host(), start_time(writer.pid))
        write_marker(tmp_path, "a000-s0000", live)
        busy = tmp_path / "runs" / f"a000-s0000.tmp-{writer.pid}-abc123"
        busy.mkdir()
        gone = Owner(writer.pid + 10**6, this_host())  # no such process
        write_marker(tmp_path, "a000-s0001", gone)
        dead = tmp_path / "runs" / "a000-s0001.tmp-1-abc123"
        dead.mkdir()
        unmarked = tmp_path / "runs" / "a000-s0002.old-1-abc123"
        unmarked.mkdir()
        clean_leftovers(tmp_path)
        assert busy.is_dir() and not dead.exists() and not unmarked.exists()
        assert list(writers(tmp_path)) == ["a000-s0000"]  # the dead writer's marker went
        notes: list[str] = []
        waited: list[int] = []
        waiter = threading.Thread(
            target=lambda: waited.append(wait_for_writers(tmp_path, notes.append))
        )
        waiter.start()
        time.sleep(1.0)
        assert waiter.is_alive() and busy.is_dir()  # waits while the writer lives
        assert f"pid {writer.pid} on host {this_host()}" in notes[0]
    finally:
        writer.kill()
        writer.wait()
    waiter.join(timeout=10)
    assert not waiter.is_alive() and waited == [1]
    clean_leftovers(tmp_path)
    assert not busy.exists()


def test_a_writer_of_another_host_lives_while_its_heartbeat_does(tmp_path: Path) -> None:
    marker = write_marker(tmp_path, "a000-s0000", Owner(1, "another-machine"))
    assert list(writers(tmp_path)) == ["a000-s0000"]
    os.utime(marker, (time.time() - 3600, time.time() - 3600))
    assert writers(tmp_path) == {} and not marker.exists()
