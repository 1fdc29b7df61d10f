"""Run logs: a replayed run equals the live one, snapshot by snapshot and row by row."""

from __future__ import annotations

import dataclasses
import json
import re
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from mresim_phys import MresimError, Simulation
from mresim_phys.output.runlog import RunLog, RunLogWriter, chunk_file, recompute_metrics
from mresim_phys.snapshot import Snapshot

ScenarioFile = Callable[..., Path]
THREE_ROBOTS = [
    {"name": "A", "start": [8, 20], "heading_deg": 0},
    {"name": "B", "start": [8, 40], "heading_deg": 0, "speed": 3},
    {"name": "C", "start": [20, 30], "heading_deg": 90},
]


def kept(snap: Snapshot) -> Snapshot:
    """A snapshot whose grids are copies (live snapshots are views of changing grids)."""
    agents = tuple(
        dataclasses.replace(a, belief=a.belief.copy(), safe=a.safe.copy()) for a in snap.agents
    )
    return dataclasses.replace(snap, agents=agents)


def record_run(
    path: Path, log_dir: Path, steps: int, chunk_steps: int = 16, close: bool = True
) -> tuple[list[Snapshot], list[list[str]], RunLogWriter]:
    """Run ``steps`` steps, logging every snapshot; the live snapshots and csv rows, the writer."""
    sim = Simulation.from_yaml(path, steps=steps)
    first = sim.snapshot()
    snaps, rows = [kept(first)], [sim.record.csv_row()]
    writer = RunLogWriter(log_dir, first, name="tiny", seed=3, chunk_steps=chunk_steps)
    for _ in range(steps):
        rows.append(sim.step().csv_row())
        snap = sim.snapshot()
        writer.write(snap)
        snaps.append(kept(snap))
    if close:
        writer.close()
    return snaps, rows, writer


def assert_same_snapshot(got: Snapshot, want: Snapshot) -> None:
    assert got.step == want.step
    assert got.events == want.events
    assert np.array_equal(got.links, want.links)
    assert np.array_equal(got.truth, want.truth)
    assert got.resolution == want.resolution
    assert (got.explored, got.known_at_base, got.alive) == (
        want.explored,
        want.known_at_base,
        want.alive,
    )
    assert len(got.agents) == len(want.agents)
    for a, b in zip(got.agents, want.agents, strict=True):
        for name in ("name", "kind", "position", "heading", "radius", "state", "role"):
            assert getattr(a, name) == getattr(b, name), (got.step, a.name, name)
        for name in ("comm_range", "goal", "distance", "parent"):
            assert getattr(a, name) == getattr(b, name), (got.step, a.name, name)
        assert a.path.shape == b.path.shape and np.array_equal(a.path, b.path)
        assert a.belief.dtype == b.belief.dtype and np.array_equal(a.belief, b.belief)
        assert a.safe.dtype == b.safe.dtype and np.array_equal(a.safe, b.safe)
        assert not a.belief.flags.writeable and not a.safe.flags.writeable


@pytest.fixture
def failing(scenario_file: ScenarioFile) -> Path:
    return scenario_file(robots=THREE_ROBOTS, events=[{"step": 10, "fail": "B"}])


def test_replayed_snapshots_equal_the_live_ones(failing: Path, tmp_path: Path) -> None:
    snaps, _, _ = record_run(failing, tmp_path / "log", 50)
    log = RunLog.open(tmp_path / "log")
    assert log.steps == 51
    assert log.names == ["base", "A", "B", "C"]
    assert log.robot_names == ["A", "B", "C"]
    assert np.array_equal(log.truth, snaps[0].truth)
    for got, want in zip(log.snapshots(), snaps, strict=True):  # grids are views: stream
        assert_same_snapshot(got, want)
    assert any(len(s.robots[0].path) for s in snaps)  # paths were exercised
    assert any(s.links.any() for s in snaps)


@pytest.mark.parametrize(
    "changes",
    [
        {},
        {"robots": THREE_ROBOTS, "events": [{"step": 10, "fail": "B"}]},
        {"robots": THREE_ROBOTS, "simulation": {"multi_hop": False}},
    ],
    ids=["default", "failure", "one-hop"],
)
def test_recomputed_metrics_equal_the_live_csv(
    scenario_file: ScenarioFile, tmp_path: Path, changes: dict[str, object]
) -> None:
    _, rows, _ = record_run(scenario_file(**changes), tmp_path / "log", 45, chunk_steps=7)
    got = [record.csv_row() for record in recompute_metrics(RunLog.open(tmp_path / "log"))]
    assert got == rows


def test_the_log_shows_the_failure(failing: Path, tmp_path: Path) -> None:
    record_run(failing, tmp_path / "log", 40)
    lines = (tmp_path / "log" / "steps.jsonl").read_text().splitlines()
    assert json.loads(lines[10])["events"] == ["fail B"]
    assert all(json.loads(line)["events"] == [] for i, line in enumerate(lines) if i != 10)
    for snap in RunLog.open(tmp_path / "log").snapshots():
        assert snap.events == (("fail B",) if snap.step == 10 else ())
        state = snap.robots[1].state
        assert (state == "failed") == (snap.step >= 10), (snap.step, state)
        assert snap.alive == (2 if snap.step >= 10 else 3)


def test_an_unclosed_log_holds_its_flushed_chunks(
    scenario_file: ScenarioFile, tmp_path: Path
) -> None:
    log_dir = tmp_path / "log"
    _, rows, writer = record_run(scenario_file(), log_dir, 40, chunk_steps=16, close=False)
    log = RunLog.open(log_dir)  # as after a crash: only whole chunks count
    assert log.steps == 32 and not log.meta["closed"]
    assert [record.csv_row() for record in recompute_metrics(log)] == rows[:32]
    writer.close()
    log = RunLog.open(log_dir)
    assert log.steps == 41 and log.meta["closed"]
    assert [record.csv_row() for record in recompute_metrics(log)] == rows


def test_writer_wants_steps_in_order(scenario_file: ScenarioFile, tmp_path: Path) -> None:
    sim = Simulation.from_yaml(scenario_file(), steps=5)
    with (
        RunLogWriter(tmp_path / "log", sim.snapshot(), name="tiny", seed=3) as writer,
        pytest.raises(ValueError, match="step 0 logged after step 0"),
    ):
        writer.write(sim.snapshot())
    assert RunLog.open(tmp_path / "log").meta["closed"]


@pytest.fixture
def small_log(scenario_file: ScenarioFile, tmp_path: Path) -> Path:
    record_run(scenario_file(), tmp_path / "log", 20, chunk_steps=8)
    return tmp_path / "log"


def replay_all(log_dir: Path) -> None:
    for _ in RunLog.open(log_dir).snapshots():
        pass


def test_a_missing_log_is_a_user_error(tmp_path: Path) -> None:
    with pytest.raises(MresimError, match="no run log here"):
        RunLog.open(tmp_path / "nowhere")


@pytest.mark.parametrize(
    ("damage", "message"),
    [
        (lambda d: (d / "meta.json").write_text("{not json"), "meta.json"),
        (lambda d: (d / "meta.json").write_text('{"format": "other"}'), "not a mresim-runlog"),
        (lambda d: (d / "truth.npz").write_bytes(b"garbage"), "truth.npz"),
        (lambda d: (d / chunk_file(1)).unlink(), "deltas-00001.npz is missing"),
        (lambda d: (d / "steps.jsonl").write_text("{}\n"), "steps.jsonl has 1 lines"),
    ],
    ids=["meta-garbled", "meta-foreign", "truth-garbled", "chunk-missing", "steps-short"],
)
def test_a_damaged_log_is_a_user_error(
    small_log: Path, damage: Callable[[Path], object], message: str
) -> None:
    damage(small_log)
    with pytest.raises(MresimError, match=re.escape(message)):
        replay_all(small_log)


def test_a_garbled_chunk_or_line_is_a_user_error(small_log: Path) -> None:
    (small_log / chunk_file(2)).write_bytes(b"PK garbage")
    with pytest.raises(MresimError, match=re.escape("deltas-00002.npz")):
        replay_all(small_log)
    lines = (small_log / "steps.jsonl").read_text().splitlines()
    (small_log / "steps.jsonl").write_text("\n".join(["[oops", *lines[1:]]) + "\n")
    with pytest.raises(MresimError, match=re.escape("steps.jsonl line 1")):
        replay_all(small_log)


def test_a_log_of_another_version_is_refused(small_log: Path) -> None:
    meta = json.loads((small_log / "meta.json").read_text())
    (small_log / "meta.json").write_text(json.dumps(meta | {"version": 99}))
    with pytest.raises(MresimError, match="version 99"):
        RunLog.open(small_log)


def test_the_log_is_small(scenario_file: ScenarioFile, tmp_path: Path) -> None:
    record_run(scenario_file(robots=THREE_ROBOTS), tmp_path / "log", 40)
    size = sum(f.stat().st_size for f in (tmp_path / "log").iterdir())
    assert size < 1_000_000
    grids = 41 * 4 * 60 * 80 * 2  # what full grids for every agent and step would take
    assert size < grids / 10


def test_the_log_keeps_bytes_per_link_and_blackouts(
    scenario_file: ScenarioFile, tmp_path: Path
) -> None:
    events = [{"step": 3, "until": 6, "blackout": ["B"]}]
    record_run(scenario_file(events=events), tmp_path / "log", 8, chunk_steps=3)
    snaps = list(RunLog.open(tmp_path / "log").snapshots())
    assert any("blackout B (both) until 6" in s.events for s in snaps)
    assert any("blackout over B (both)" in s.events for s in snaps)
    for snap in snaps:
        sent = snap.comm.link_bytes
        assert sent is not None and sent.sum() == snap.comm.comm_bytes
        if 3 <= snap.step < 6:
            assert not sent[2].any() and not sent[:, 2].any()  # B (agent 2) is silent
    assert snaps[0].comm.comm_bytes > 0
