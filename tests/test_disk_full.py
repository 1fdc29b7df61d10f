"""A disk that fills up: every output either appears whole under its name or not at all, and
the command exits non-zero with a one-paragraph message naming the file and the cause.

Real processes get a file size limit (``RLIMIT_FSIZE``, SIGXFSZ ignored: writes past it
fail with EFBIG, as writes to a full disk fail with ENOSPC), so OpenCV's encoder, libpng
and Python's own files fail for real; in-process tests make one rename fail with ENOSPC.
"""

from __future__ import annotations

import errno
import json
import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import cv2
import numpy as np
import pytest

from mresim_phys.cli import main
from mresim_phys.columns import Layout
from mresim_phys.output.files import PendingFile, WriteError
from mresim_phys.output.logwriter import RunLogWriter
from mresim_phys.output.runlog import RunLog, recompute_metrics
from mresim_phys.output.video import VideoRecorder, frames_in
from mresim_phys.sim import Simulation

ScenarioFile = Callable[..., Path]
EARLIER = {"name": "tiny", "seed": 3, "steps": 5, "marker": "an earlier run"}
FULL = os.strerror(errno.ENOSPC)  # "No space left on device"

# Runs the CLI under a file size limit, after a short run without one, so that numba's
# cache (written on first use) is in place before writes start failing.
LIMITED = """
import resource, signal, sys
from mresim_phys.cli import main
from mresim_phys.columns import Layout
limit, warm, args = int(sys.argv[1]), sys.argv[2], sys.argv[3:]
main(["run", args[1], "--out", warm, "--steps", "3", "--quiet", "--no-plots"])
signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
resource.setrlimit(resource.RLIMIT_FSIZE, (limit, resource.getrlimit(resource.RLIMIT_FSIZE)[1]))
sys.exit(main(args))
"""


def leftovers(folder: Path) -> list[Path]:
    """Temporary files and run folders (``.x.tmp-...``, ``out.tmp-...``) under ``folder``."""
    return [p for p in folder.rglob("*") if ".tmp-" in p.name]


def earlier_run(out: Path) -> Path:
    """An output folder holding an earlier run of the same scenario."""
    out.mkdir(parents=True)
    (out / "summary.json").write_text(json.dumps(EARLIER))
    return out


def assert_kept(out: Path) -> None:
    """``out`` holds the earlier run, exactly as before."""
    assert sorted(p.name for p in out.iterdir()) == ["summary.json"]
    assert json.loads((out / "summary.json").read_text()) == EARLIER


def the_message(stderr: str) -> str:
    """The error paragraph (one line) of a failed command, checked to be the only one."""
    assert "Traceback" not in stderr
    lines = [line for line in stderr.splitlines() if line.startswith("mresim:")]
    assert len(lines) == 1, stderr
    return lines[0]


def fail_renames_onto(monkeypatch: pytest.MonkeyPatch, name: str) -> None:
    """Renaming a file onto ``name`` fails as on a full disk."""
    real = os.replace

    def replace(src: str | Path, dst: str | Path) -> None:
        if Path(dst).name == name:
            raise OSError(errno.ENOSPC, FULL)
        real(src, dst)

    monkeypatch.setattr(os, "replace", replace)


# --- real processes under a file size limit ------------------------------------------


@pytest.mark.parametrize(
    ("limit", "flags", "failing"),
    [
        (5_000, ["--no-log"], "out/metrics.csv"),  # a stream, mid-run
        (20_000, [], "out/log/steps.jsonl"),
        (30_000, ["--no-log"], "out/final.png"),  # libpng says only "Write Error"
        (150_000, ["--no-log", "--video", "videos/v.mp4"], "videos/v.mp4"),  # OpenCV: nothing
    ],
    ids=["metrics", "log", "final-png", "video"],
)
def test_a_run_that_fills_the_disk_fails_and_keeps_the_earlier_run(
    tmp_path: Path, scenario_file: ScenarioFile, limit: int, flags: list[str], failing: str
) -> None:
    scenario, out = scenario_file(steps=200), earlier_run(tmp_path / "out")
    (tmp_path / "videos").mkdir()  # mresim creates no folder a --video path names
    args = ["run", str(scenario), "--out", "out", "--quiet", "--no-plots", *flags]
    command = [sys.executable, "-c", LIMITED, str(limit), "warm", *args]
    done = subprocess.run(command, cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert done.returncode == 2, done.stderr
    message = the_message(done.stderr)
    assert message.startswith(f"mresim: error: cannot write {failing}: File too large.")
    assert "out still holds what it held before" in message
    assert_kept(out)
    assert not leftovers(tmp_path)
    assert not list((tmp_path / "videos").iterdir())


# --- in process: one rename fails with ENOSPC ------------------------------------------


def test_a_video_finished_before_the_summary_failed_is_kept(
    tmp_path: Path,
    scenario_file: ScenarioFile,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    out, video = earlier_run(tmp_path / "out"), tmp_path / "v.mp4"
    fail_renames_onto(monkeypatch, "summary.json")
    flags = ["--out", str(out), "--video", str(video), "--quiet", "--no-plots", "--steps", "12"]
    assert main(["run", str(scenario_file()), *flags]) == 2
    message = the_message(capsys.readouterr().err)
    assert message.startswith(f"mresim: error: cannot write {out / 'summary.json'}: {FULL}.")
    assert_kept(out)
    capture = cv2.VideoCapture(str(video))  # finished before: whole, every frame readable
    readable = sum(1 for _ in iter(lambda: capture.read()[0], False))
    assert frames_in(video) == readable == 13
    assert not leftovers(tmp_path)


def test_a_plot_that_cannot_be_written_leaves_the_finished_ones(
    tmp_path: Path,
    scenario_file: ScenarioFile,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    run, plots = tmp_path / "run", tmp_path / "plots"
    assert main(["run", str(scenario_file()), "--out", str(run), "--quiet", "--no-plots"]) == 0
    fail_renames_onto(monkeypatch, "links.png")
    assert main(["plot", str(run), "--out", str(plots)]) == 2
    message = the_message(capsys.readouterr().err)
    assert message.startswith(f"mresim: error: cannot write {plots / 'links.png'}: {FULL}.")
    assert sorted(p.name for p in plots.iterdir()) == ["distance.png", "exploration.png"]
    assert all(cv2.imread(str(p)) is not None for p in plots.iterdir())
    assert not leftovers(tmp_path)


def test_a_log_that_cannot_commit_a_chunk_keeps_the_chunks_before(
    tmp_path: Path, scenario_file: ScenarioFile, monkeypatch: pytest.MonkeyPatch
) -> None:
    sim, log_dir = Simulation.from_yaml(scenario_file(), steps=30), tmp_path / "log"
    layout = Layout.of([r.name for r in sim.robots], latest=True, faults=True)
    rows = [layout.row(sim.record)]
    writer = RunLogWriter(log_dir, sim.snapshot(), name="tiny", seed=3, chunk_steps=8)
    fail_renames_onto(monkeypatch, "deltas-00001.npz")
    with pytest.raises(WriteError, match=f"deltas-00001.npz: {FULL}"):
        for _ in range(30):
            rows.append(layout.row(sim.step()))
            writer.write(sim.snapshot())
    writer.close()  # commits nothing more
    log = RunLog.open(log_dir)
    assert log.steps == 8 and not log.meta["closed"]
    assert [layout.row(r) for r in recompute_metrics(log)] == rows[:8]
    assert not (log_dir / "deltas-00001.npz").exists() and not leftovers(tmp_path)


class SilentWriter:
    """Stands in for cv2.VideoWriter on a full disk: every frame "written", none stored."""

    fourcc = staticmethod(cv2.VideoWriter.fourcc)

    def __init__(self, path: str, *args: object) -> None:
        Path(path).write_bytes(b"\0" * 100)  # a header, then nothing

    def isOpened(self) -> bool:
        return True

    def write(self, frame: np.ndarray) -> None:
        pass

    def release(self) -> None:
        pass


def test_a_video_the_encoder_failed_silently_is_not_given_its_name(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(cv2, "VideoWriter", SilentWriter)
    video = VideoRecorder(tmp_path / "x.mp4", 10, (32, 24), fourcc="mp4v")  # OpenCV's encoder
    for _ in range(3):
        video.write(np.zeros((24, 32, 3), np.uint8))
    with pytest.raises(WriteError, match=r"x\.mp4: the encoder failed silently \(0 of the 3"):
        video.close()
    assert list(tmp_path.iterdir()) == []


def test_a_stream_that_cannot_be_committed_never_pretends_it_was(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    (tmp_path / "rows.csv").write_text("earlier\n")
    pending = PendingFile(tmp_path / "rows.csv")
    pending.write("step\n0\n")
    fail_renames_onto(monkeypatch, "rows.csv")
    for _ in range(2):  # committing again says so again
        with pytest.raises(WriteError, match=f"rows.csv: {FULL}"):
            pending.commit()
    assert [p.name for p in tmp_path.iterdir()] == ["rows.csv"]
    assert (tmp_path / "rows.csv").read_text() == "earlier\n"


def test_a_manifest_line_that_cannot_be_written_leaves_no_half_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A full disk while noting a run: a WriteError naming the manifest, the file as it was
    (no partial line for the next record to join), and the next record read back."""
    import errno
    import os as os_module

    from mresim_phys.output.files import WriteError
    from mresim_phys.sweeps import manifest as manifest_module

    book = manifest_module.Manifest(tmp_path, {})
    record = {"run_id": "r1", "status": "done", "attempt": 1}
    book.add(record)
    before = (tmp_path / manifest_module.MANIFEST).read_bytes()
    real_fsync = os_module.fsync

    def full(fd: int) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(manifest_module.os, "fsync", full)
    with pytest.raises(WriteError, match=r"manifest.*No space left on device"):
        book.add({**record, "run_id": "r2"})
    monkeypatch.setattr(manifest_module.os, "fsync", real_fsync)
    assert (tmp_path / manifest_module.MANIFEST).read_bytes() == before
    book.add({**record, "run_id": "r3"})
    lines = (tmp_path / manifest_module.MANIFEST).read_text().splitlines()
    assert [json.loads(line)["run_id"] for line in lines] == ["r1", "r3"]
