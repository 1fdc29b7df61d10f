"""Interrupted runs keep their outputs: SIGINT, SIGTERM and SIGKILL against real processes.

``tools/interrupt_trials.py`` runs 20 trials of each signal and progress-bar combination;
here one of each (the trial code is the tool's).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from tool_modules import load_tool

from mresim_phys.output.session import run_session
from mresim_phys.output.signals import StopRequest, stop_on_signals
from mresim_phys.sim import Simulation

trials = load_tool("interrupt_trials")

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


@pytest.fixture(autouse=True)
def ctrl_c_reaches_children() -> Iterator[None]:
    """Runs started by a pytest in a shell's background would ignore SIGINT."""
    before = signal.getsignal(signal.SIGINT)
    trials.ctrl_c_reaches_children()
    yield
    if before is not None:
        signal.signal(signal.SIGINT, before)


@pytest.mark.parametrize(
    ("sig", "bar", "double"),
    [
        (signal.SIGINT, True, True),
        (signal.SIGINT, False, False),
        (signal.SIGTERM, True, False),
        (signal.SIGTERM, False, True),
    ],
    ids=["SIGINT-bar-twice", "SIGINT-quiet", "SIGTERM-bar", "SIGTERM-quiet-twice"],
)
def test_a_signalled_run_keeps_every_output(
    tmp_path: Path, sig: signal.Signals, bar: bool, double: bool
) -> None:
    result = trials.trial(tmp_path, sig, bar, double)
    assert result.lost == []
    assert not list(tmp_path.glob("run.tmp-*")), "the temporary folder was moved into place"


def test_a_killed_run_leaves_the_previous_run_whole(tmp_path: Path) -> None:
    scenario, out = trials.long_scenario(tmp_path), tmp_path / "run"
    out.mkdir()
    before = {"name": "interrupt-trial", "steps": 5, "marker": "the previous run"}
    (out / "summary.json").write_text(json.dumps(before))
    video = tmp_path / "videos" / "v.mp4"
    video.parent.mkdir()  # a folder a video path names must exist
    flags = ["--out", out, "--quiet", "--no-plots", "--video", video]
    process = subprocess.Popen(trials.mresim("run", scenario, *flags))
    deadline = time.monotonic() + trials.STARTUP_TIMEOUT_S
    while not trials.rows_on_disk(out) and time.monotonic() < deadline:
        time.sleep(0.02)
    process.kill()
    assert process.wait() == -signal.SIGKILL
    assert json.loads((out / "summary.json").read_text()) == before
    assert sorted(p.name for p in out.iterdir()) == ["summary.json"]
    assert not video.exists()  # the video is renamed into place only when finished


def test_handlers_are_restored_after_a_session(
    scenario_file: Callable[..., Path], tmp_path: Path
) -> None:
    before = [signal.getsignal(s) for s in STOP_SIGNALS]
    sim = Simulation.from_yaml(scenario_file(steps=3))
    run_session(sim, tmp_path / "out")
    assert [signal.getsignal(s) for s in STOP_SIGNALS] == before


def test_a_signal_inside_a_session_stops_it_after_the_step(
    scenario_file: Callable[..., Path], tmp_path: Path
) -> None:
    sim = Simulation.from_yaml(scenario_file(steps=50))

    def signal_at_step_4(record: object) -> None:
        if sim.t == 4:
            os.kill(os.getpid(), signal.SIGTERM)
            os.kill(os.getpid(), signal.SIGINT)  # ignored: already stopping

    outcome = run_session(sim, tmp_path / "out", signal_at_step_4)
    assert (outcome.reason, outcome.signal, outcome.exit_status) == ("interrupted", "SIGTERM", 143)
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert (summary["steps"], summary["stop_reason"], summary["signal"]) == (
        4,
        "interrupted",
        "SIGTERM",
    )
    assert (tmp_path / "out" / "final.png").is_file()


def test_simulation_run_keeps_pythons_ctrl_c(scenario_file: Callable[..., Path]) -> None:
    sim = Simulation.from_yaml(scenario_file(steps=50))

    def ctrl_c(record: object) -> None:
        if sim.t == 2:
            os.kill(os.getpid(), signal.SIGINT)

    with pytest.raises(KeyboardInterrupt):
        sim.run(ctrl_c)
    assert sim.t == 2


def test_outside_the_main_thread_no_handler_is_installed(
    scenario_file: Callable[..., Path], tmp_path: Path
) -> None:
    sim = Simulation.from_yaml(scenario_file(steps=3))
    outcomes = []
    worker = threading.Thread(target=lambda: outcomes.append(run_session(sim, tmp_path / "o")))
    worker.start()
    worker.join()
    assert [o.reason for o in outcomes] == ["steps"]


def test_an_ignored_signal_stays_ignored() -> None:
    previous = signal.signal(signal.SIGTERM, signal.SIG_IGN)
    try:
        with stop_on_signals(StopRequest(notice=False)) as stop:
            assert signal.getsignal(signal.SIGTERM) is signal.SIG_IGN
            assert signal.getsignal(signal.SIGINT) == stop.handle
        assert signal.getsignal(signal.SIGTERM) is signal.SIG_IGN
    finally:
        signal.signal(signal.SIGTERM, previous)


def test_a_stopped_program_keeps_ignoring_stop_signals_until_it_exits() -> None:
    before = [signal.getsignal(s) for s in STOP_SIGNALS]
    try:
        with stop_on_signals(StopRequest(notice=False), linger=True):
            pass  # no signal: the handlers come back
        assert [signal.getsignal(s) for s in STOP_SIGNALS] == before
        with stop_on_signals(StopRequest(notice=False), linger=True):
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(0.01)
        assert [signal.getsignal(s) for s in STOP_SIGNALS] == [signal.SIG_IGN] * 2
    finally:
        for s, handler in zip(STOP_SIGNALS, before, strict=True):
            signal.signal(s, handler)
