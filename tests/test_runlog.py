"""Run logs: a replayed run equals the live one, snapshot by snapshot and row by row."""

from __future__ import annotations

import copy
import dataclasses
import json
import re
from collections.abc import Callable, Collection
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pytest
from conftest import csv_row

from mresim_phys import MresimError, Simulation
from mresim_phys.output import logformat
from mresim_phys.output.replay import replay_frames
from mresim_phys.output.runlog import (
    Replay,
    RunLog,
    RunLogWriter,
    chunk_file,
    reachable_from,
    recompute_metrics,
)
from mresim_phys.render import LayerSpec, Renderer, frame_scale
from mresim_phys.render.draw import robot_label
from mresim_phys.scenario.run_specs import RenderSpec
from mresim_phys.snapshot import AgentSnapshot, CommSummary, Snapshot
from mresim_phys.world.explorable import follow_world
from mresim_phys.world.maps import free_components_mask

ScenarioFile = Callable[..., Path]
THREE_ROBOTS = [
    {"name": "A", "start": [8, 20], "heading_deg": 0},
    {"name": "B", "start": [8, 40], "heading_deg": 0, "speed": 3},
    {"name": "C", "start": [20, 30], "heading_deg": 90},
]


def kept(snap: Snapshot) -> Snapshot:
    """A snapshot whose arrays are copies (live snapshots are views of changing grids)."""
    return copy.deepcopy(snap)


def record_run(
    path: Path, log_dir: Path, steps: int, chunk_steps: int = 16, close: bool = True
) -> tuple[list[Snapshot], list[list[str]], RunLogWriter]:
    """Run ``steps`` steps, logging every snapshot; the live snapshots and csv rows, the writer."""
    sim = Simulation.from_yaml(path, steps=steps)
    first = sim.snapshot()
    snaps, rows = [kept(first)], [csv_row(sim.record)]
    writer = RunLogWriter(log_dir, first, name="tiny", seed=3, chunk_steps=chunk_steps)
    for _ in range(steps):
        rows.append(csv_row(sim.step()))
        snap = sim.snapshot()
        writer.write(snap)
        snaps.append(kept(snap))
    if close:
        writer.close()
    return snaps, rows, writer


def assert_same(got: Any, want: Any, where: str, skip: Collection[str] = ()) -> None:
    """``got`` equals ``want``: dataclasses field by field (every field but ``skip``),
    arrays in dtype, shape and values, sequences item by item, anything else by ``==``."""
    if dataclasses.is_dataclass(want):
        assert type(got) is type(want), where
        for f in dataclasses.fields(want):
            if f.name not in skip:
                assert_same(getattr(got, f.name), getattr(want, f.name), f"{where}.{f.name}", skip)
    elif isinstance(want, np.ndarray) or isinstance(got, np.ndarray):
        assert isinstance(got, np.ndarray) and isinstance(want, np.ndarray), where
        assert (got.dtype, got.shape) == (want.dtype, want.shape), where
        assert np.array_equal(got, want), where
    elif isinstance(want, tuple | list):
        assert type(got) is type(want) and len(got) == len(want), where
        for i, (a, b) in enumerate(zip(got, want, strict=True)):
            assert_same(a, b, f"{where}[{i}]", skip)
    else:
        assert got == want, (where, got, want)


def assert_same_snapshot(got: Snapshot, want: Snapshot, skip: Collection[str] = ()) -> None:
    """Every field of every snapshot and agent equal; the replayed grids read-only."""
    assert_same(got, want, f"step {want.step}", skip)
    assert not got.truth.flags.writeable
    for agent in got.agents:
        grids = [agent.belief, agent.safe] + ([] if agent.skeleton is None else [agent.skeleton])
        assert not any(grid.flags.writeable for grid in grids), agent.name


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
    assert any(s.base.base_contact > 0 for s in snaps)  # the base's own contact step too


def test_planner_views_replay(scenario_file: ScenarioFile, tmp_path: Path) -> None:
    """Views a planner puts in Decision.info (the topological skeleton) replay too."""
    robots = [{**r, "planner": "topological"} for r in THREE_ROBOTS]
    robots[1]["planner"] = {"name": "topological", "params": {"smooth": True}}
    snaps, rows, _ = record_run(scenario_file(robots=robots), tmp_path / "log", 30)
    log = RunLog.open(tmp_path / "log")
    for got, want in zip(log.snapshots(), snaps, strict=True):
        assert_same_snapshot(got, want)
    assert sum(r.skeleton is not None and r.skeleton.any() for r in snaps[-1].robots) == 3
    assert [csv_row(record) for record in recompute_metrics(log)] == rows


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
    got = [csv_row(record) for record in recompute_metrics(RunLog.open(tmp_path / "log"))]
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


def test_part_failures_are_logged_replayed_and_drawn(
    scenario_file: ScenarioFile, tmp_path: Path
) -> None:
    """A robot that lost its radio stays 'active' in metrics, but the log, the replay and
    the frame's label say what broke."""
    events = [{"step": 5, "fail": "B", "part": "radio"}, {"step": 8, "fail": "C", "part": "drive"}]
    snaps, _, _ = record_run(
        scenario_file(robots=THREE_ROBOTS, events=events), tmp_path / "log", 12
    )
    assert [r.features.get("parts") for r in snaps[-1].robots] == [None, {"radio"}, {"drive"}]
    assert "parts" not in snaps[4].robots[1].features
    lines = (tmp_path / "log" / "steps.jsonl").read_text().splitlines()
    assert "parts" not in json.loads(lines[4])["agents"][2]  # nothing broken: nothing stored
    assert json.loads(lines[-1])["agents"][2]["parts"] == ["radio"]
    for got, want in zip(RunLog.open(tmp_path / "log").snapshots(), snaps, strict=True):
        assert_same_snapshot(got, want)
    assert robot_label(snaps[-1].robots[1]) == "B [radio]"
    assert robot_label(snaps[-1].robots[0]) == "A"


def downgrade_to_version_6(log_dir: Path) -> None:
    """Rewrite a log's agent lines as version 6 wrote them: the broken parts under
    ``broken``, the teammates presumed lost under ``presumed_lost``, the reason of a change
    of state under ``state_reason``."""
    meta = json.loads((log_dir / "meta.json").read_text())
    (log_dir / "meta.json").write_text(json.dumps(meta | {"version": 6}))
    lines = [json.loads(line) for line in (log_dir / "steps.jsonl").read_text().splitlines()]
    for line in lines:
        line["agents"] = [old_agent_line(agent) for agent in line["agents"]]
    (log_dir / "steps.jsonl").write_text("".join(json.dumps(line) + "\n" for line in lines))


def old_agent_line(agent: dict[str, Any]) -> dict[str, Any]:
    """An agent's line as version 6 wrote it."""
    renamed = {"parts": "broken", "lost": "presumed_lost", "health": "state_reason"}
    return {renamed.get(key, key): value for key, value in agent.items()}


def test_version_6_logs_still_replay_their_broken_parts_lost_teammates_and_reasons(
    scenario_file: ScenarioFile, tmp_path: Path
) -> None:
    events = [{"step": 3, "fail": "B", "part": "radio"}, {"step": 5, "fail": "C", "part": "drive"}]
    events.append({"step": 9, "fail": "A"})
    path = scenario_file(robots=THREE_ROBOTS, events=events, simulation={"presume_lost_after": 4})
    snaps, rows, _ = record_run(path, tmp_path / "log", 14, chunk_steps=4)
    downgrade_to_version_6(tmp_path / "log")
    text = (tmp_path / "log" / "steps.jsonl").read_text()
    assert '"broken": ["radio"]' in text and '"presumed_lost": ["B"]' in text
    assert '"state_reason": "fail A"' in text
    log = RunLog.open(tmp_path / "log")
    for got, want in zip(log.snapshots(), snaps, strict=True):
        assert_same_snapshot(got, want)
    assert [csv_row(record) for record in recompute_metrics(log)] == rows


def test_an_unclosed_log_holds_its_flushed_chunks(
    scenario_file: ScenarioFile, tmp_path: Path
) -> None:
    log_dir = tmp_path / "log"
    _, rows, writer = record_run(scenario_file(), log_dir, 40, chunk_steps=16, close=False)
    log = RunLog.open(log_dir)  # as after a crash: only whole chunks count
    assert log.steps == 32 and not log.meta["closed"]
    assert [csv_row(record) for record in recompute_metrics(log)] == rows[:32]
    writer.close()
    log = RunLog.open(log_dir)
    assert log.steps == 41 and log.meta["closed"]
    assert [csv_row(record) for record in recompute_metrics(log)] == rows


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


def hand_agent(name: str, step: int, rng: np.random.Generator, **fields: Any) -> AgentSnapshot:
    """An agent with random grids on a 6x10 map and values that change with ``step``."""
    values: dict[str, Any] = {"kind": "robot", "position": (1.5 + step, 2.25), "radius": 1.5}
    values |= {"heading": 0.1 * step, "state": "active", "role": "explorer", "comm_range": 7.0}
    values |= {"goal": (8.0, 4.5) if step % 2 else None, "distance": 0.75 * step}
    values |= {"base_contact": step - 1}
    belief = rng.integers(0, 3, (6, 10)).astype(np.uint8)
    return AgentSnapshot(
        name=name, belief=belief, safe=rng.random((6, 10)) < 0.3, **values | fields
    )


def hand_snapshots() -> list[Snapshot]:
    """Five steps in which every optional field goes from None to a value and back, paths
    are followed and replaced, and the world changes twice."""
    rng, truth = np.random.default_rng(5), np.zeros((6, 10), dtype=bool)
    truth[0, :] = True
    skeleton = rng.random((6, 10)) < 0.2
    plans = [[[1, 1], [2, 2], [3, 3]], [[2, 2], [3, 3]], [[9, 1.5]], [], [[0.5, 0.25]]]
    points = [None, [[1, 2], [3.5, 4]], [[3.5, 4]], None, np.zeros((0, 2))]
    skeletons = [None, skeleton, skeleton, ~skeleton, None]
    closed = truth | (np.arange(10) == 7)  # a wall appears in column 7
    truths = [(0, truth), (0, truth), (1, closed), (1, closed), (2, ~truth)]
    truths[4][1][2, 1] = False  # the robot's start stays free
    snaps = []
    for step in range(5):
        version, grid = truths[step]
        base = hand_agent("base", step, rng, kind="base", state="base", role="base", radius=0.0)
        rendezvous = None if points[step] is None else np.array(points[step], float)
        path = np.array(plans[step], float).reshape(-1, 2)
        parent = "base" if step in (1, 2) else None
        robot = hand_agent("R", step, rng, path=path, rendezvous=rendezvous, parent=parent)
        robot = dataclasses.replace(robot, skeleton=skeletons[step])
        links = np.array([[False, step % 2 == 1], [step % 2 == 1, False]])
        sent = np.array([[0, 3 * step], [step, 0]], dtype=np.int64)
        comm = CommSummary(4 * step, links.copy(), step, 2.0 * step, 0.5 * step, sent)
        snaps.append(
            Snapshot(
                step=step,
                explored=0.0,
                known_at_base=0.0,
                alive=1,
                truth=grid.copy(),
                agents=(base, robot),
                links=links,
                events=(f"event {step}",) * (step % 2),
                resolution=0.05,
                comm=comm,
                world_version=version,
            )
        )
    return snaps


def test_every_field_of_hand_built_snapshots_replays(tmp_path: Path) -> None:
    snaps = hand_snapshots()
    with RunLogWriter(tmp_path / "log", snaps[0], name="hand", seed=1, chunk_steps=2) as writer:
        for snap in snaps[1:]:
            writer.write(snap)
    replayed = RunLog.open(tmp_path / "log").snapshots()
    for got, want in zip(replayed, snaps, strict=True):
        # recomputed from the deltas: the metrics and each robot's activity (feature health)
        robots = [dataclasses.replace(a, features=without_health(a)) for a in got.agents]
        got = dataclasses.replace(got, agents=tuple(robots))
        assert_same_snapshot(got, want, skip=logformat.RECOMPUTED)
        assert got.alive == 1 and 0 < got.explored <= 1


def without_health(agent: AgentSnapshot) -> dict[str, Any]:
    """An agent's feature values but its run health (activity, reason)."""
    return {key: value for key, value in agent.features.items() if key != "health"}


def test_a_snapshot_field_without_a_codec_is_refused(monkeypatch: pytest.MonkeyPatch) -> None:
    logformat.check_codecs()  # as shipped: every field has one

    @dataclasses.dataclass(frozen=True)
    class WithFuel(AgentSnapshot):
        fuel: float = 1.0  # a field someone adds to AgentSnapshot

    stored = logformat.stored_fields()[AgentSnapshot]
    monkeypatch.setattr(logformat, "stored_fields", lambda: {WithFuel: stored})
    with pytest.raises(TypeError, match=re.escape("fields without a codec ['fuel']")):
        logformat.check_codecs()
    monkeypatch.undo()
    monkeypatch.setitem(logformat.AGENT_LINE, "skeleton", logformat.AGENT_LINE["heading"])
    with pytest.raises(TypeError, match=re.escape("with two codecs ['skeleton']")):
        logformat.check_codecs()


def downgrade_to_version_1(log_dir: Path) -> None:
    """Rewrite a log as version 1 wrote it: no skeletons, rendezvous points, truth changes,
    world versions or base contact of the base."""
    meta = json.loads((log_dir / "meta.json").read_text())
    (log_dir / "meta.json").write_text(json.dumps(meta | {"version": 1}))
    lines = [json.loads(line) for line in (log_dir / "steps.jsonl").read_text().splitlines()]
    for line in lines:
        del line["world_version"], line["agents"][0]["base_contact"]
    (log_dir / "steps.jsonl").write_text("".join(json.dumps(line) + "\n" for line in lines))
    for path in log_dir.glob("deltas-*.npz"):
        with np.load(path) as data:
            kept_arrays = {k: data[k] for k in data.files if k.split("_")[0] in ("belief", "safe")}
            kept_arrays |= {k: data[k] for k in data.files if k.split("_")[0] == "path"}
        np.savez_compressed(path, **kept_arrays)


def test_version_1_logs_still_replay(scenario_file: ScenarioFile, tmp_path: Path) -> None:
    robots = [THREE_ROBOTS[0], {**THREE_ROBOTS[1], "planner": "topological"}]
    snaps, rows, _ = record_run(scenario_file(robots=robots), tmp_path / "log", 25, chunk_steps=8)
    downgrade_to_version_1(tmp_path / "log")
    log = RunLog.open(tmp_path / "log")
    for got, want in zip(log.snapshots(), snaps, strict=True):
        base = dataclasses.replace(want.base, base_contact=-1)  # version 1 did not log these
        robots_then = [dataclasses.replace(r, skeleton=None, rendezvous=None) for r in want.robots]
        assert_same_snapshot(got, dataclasses.replace(want, agents=(base, *robots_then)))
    assert any(r.skeleton is not None for r in snaps[-1].robots)
    assert [csv_row(record) for record in recompute_metrics(log)] == rows


DOOR = (slice(25, 37), slice(40, 42))  # the door between the two rooms of the tiny map
CHANGES = {8: (DOOR, True), 20: ((slice(25, 31), DOOR[1]), False)}  # closed, then half open


def change_world(sim: Simulation, cells: tuple[slice, slice], occupied: bool) -> None:
    """Change the truth, as a ``cells`` event does; the coverage's cells follow."""
    rows, cols = cells
    change = sim.world.set_cells((rows.start, rows.stop, cols.start, cols.stop), occupied)
    setup = sim.setup
    follow_world(sim.coverage, setup.reachable, setup.explorable, sim.world.occupied, [change])


def test_replay_follows_truth_changes(scenario_file: ScenarioFile, tmp_path: Path) -> None:
    sim = Simulation.from_yaml(scenario_file(robots=THREE_ROBOTS), steps=30)
    # the scale run outputs use on this small map (scaled up to a 640-pixel side)
    renderer = Renderer(sim.world.shape, LayerSpec.all(), frame_scale(sim.world.shape, 2.0))
    snap = sim.snapshot()
    writer = RunLogWriter(tmp_path / "log", snap, name="tiny", seed=3, chunk_steps=8)
    snaps, rows, frames = [kept(snap)], [csv_row(sim.record)], [renderer.render(snap)]
    totals = [sim.coverage.total]
    for step in range(1, 31):
        if step in CHANGES:
            change_world(sim, *CHANGES[step])
        rows.append(csv_row(sim.step()))
        snap = sim.snapshot()
        writer.write(snap)
        snaps.append(kept(snap))
        frames.append(renderer.render(snap))
        totals.append(sim.coverage.total)
    writer.close()
    assert len(set(totals)) == 3  # each change moved the reachable set
    log = RunLog.open(tmp_path / "log")
    replay = Replay(log)
    for (got, _), want, frame, total in zip(replay.run(), snaps, frames, totals, strict=True):
        assert_same_snapshot(got, want)
        assert replay.coverage.total == total
        assert np.array_equal(renderer.render(got), frame)
        assert got.truth[33, 40] == (got.step >= 8)
        assert got.truth[27, 40] == (8 <= got.step < 20)
    assert [csv_row(record) for record in recompute_metrics(log)] == rows
    for n in range(31):  # the truth is logged only where it changed
        chunk = log.read_chunk(n // 8)
        cells = logformat.segment(chunk, "truth", n % 8)
        assert (cells.stop > cells.start) == (n in CHANGES), n
    spec = RenderSpec(layers="all", scale=2.0, snapshots=[9, 25])
    replay_frames(log, spec, tmp_path)  # as `mresim replay --snapshot 9,25` does
    for step in (9, 25):
        picture = cv2.imread(str(tmp_path / f"replay-step-{step:05d}.png"), cv2.IMREAD_COLOR)
        assert np.array_equal(picture, frames[step])


def test_a_start_buried_by_a_change_stops_seeding() -> None:
    truth = np.zeros((4, 9), dtype=bool)
    truth[:, 4] = True  # two rooms, a start in each
    starts = [[1.5, 1.5], [7.5, 2.5]]
    assert np.array_equal(reachable_from(truth, starts), free_components_mask(truth, starts))
    truth[2, 7] = True  # the right room's start is buried: only the left room is reachable
    assert np.array_equal(reachable_from(truth, starts), free_components_mask(truth, starts[0]))
    truth[1, 1] = True
    assert not reachable_from(truth, starts).any()
