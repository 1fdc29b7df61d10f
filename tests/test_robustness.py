"""Robustness metrics: knowledge lost at failures, recovery, areas, paired runs, bad input."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import cv2
import numpy as np
import pytest
from test_runlog import assert_same_snapshot, record_run

from mresim_phys.cli import main
from mresim_phys.knowledge.robustness import FailureWatch, FaultState
from mresim_phys.metrics import normalised_area
from mresim_phys.output.robustness import SIDES, comparison
from mresim_phys.output.runlog import RunLog, recompute_metrics
from mresim_phys.render import DEFAULT_STYLE
from mresim_phys.sim import Simulation
from mresim_phys.types import FREE, OCCUPIED, UNKNOWN

ScenarioFile = Callable[..., Path]
SHAPE = (4, 6)


def grid(free: list[tuple[int, int]], walls: tuple[tuple[int, int], ...] = ()) -> np.ndarray:
    """A SHAPE belief: UNKNOWN but ``free`` (FREE) and ``walls`` (OCCUPIED)."""
    belief = np.full(SHAPE, UNKNOWN, dtype=np.uint8)
    for cell in free:
        belief[cell] = FREE
    for cell in walls:
        belief[cell] = OCCUPIED
    return belief


def state(name: str, belief: np.ndarray, failed: bool = False, *parts: str) -> FaultState:
    return FaultState(name, belief, failed, frozenset(parts))


def flat(*cells: tuple[int, int]) -> list[int]:
    return sorted(r * SHAPE[1] + c for r, c in cells)


def test_knowledge_lost_and_unreported_by_hand() -> None:
    reachable = np.ones(SHAPE, dtype=bool)
    reachable[3, 5] = False  # A holds it FREE, but it is not reachable free space
    a_cells = [(0, 0), (0, 1), (0, 2), (1, 0), (1, 1), (3, 5)]
    a = grid(a_cells, walls=((2, 2),))
    b = grid([(0, 2), (2, 0)])  # B knew (0, 2) too
    base = grid([(0, 0)])  # the base heard of (0, 0)
    c = grid([(1, 1)])  # C knew (1, 1) but fails with A: it does not save it
    watch = FailureWatch(["A", "B", "C"])
    alive = [state("A", a), state("B", b), state("C", c)]
    assert watch.update(4, alive, base, reachable, 23) == []
    failing = [state("A", a, True), state("B", b), state("C", c, True)]
    new = watch.update(5, failing, base, reachable, 23)
    assert [f.robot for f in new] == ["A", "C"]
    a_fail = new[0]
    # A knew (0,0) (0,1) (0,2) (1,0) (1,1); the base (0,0); B, still speaking, (0,2)
    assert a_fail.unreported == 4  # all but (0, 0)
    assert sorted(a_fail.lost.tolist()) == flat((0, 1), (1, 0), (1, 1))
    summary = a_fail.summary()
    assert summary["knowledge_lost"] == 3
    assert summary["knowledge_lost_fraction"] == pytest.approx(3 / 23)
    assert summary["knowledge_unreported"] == 4
    assert summary["parts"] == ["robot"] and summary["silenced"]
    assert watch.columns() == (2, 3 + 1, 3 + 1)  # C lost (1, 1) as well
    assert watch.lost_mask is not None
    assert sorted(np.flatnonzero(watch.lost_mask).tolist()) == flat((0, 1), (1, 0), (1, 1))


def test_recovery_by_the_team_then_the_base() -> None:
    reachable = np.ones(SHAPE, dtype=bool)
    a = grid([(0, 1), (0, 2)])
    b, base = grid([]), grid([])
    watch = FailureWatch(["A", "B"])
    watch.update(0, [state("A", a), state("B", b)], base, reachable, 24)
    watch.update(10, [state("A", a, True), state("B", b)], base, reachable, 24)
    assert watch.columns() == (1, 2, 2)
    b[0, 1] = FREE
    watch.update(11, [state("A", a, True), state("B", b)], base, reachable, 24)
    assert watch.columns() == (1, 2, 1)
    b[0, 2] = FREE
    watch.update(13, [state("A", a, True), state("B", b)], base, reachable, 24)
    assert watch.columns() == (1, 2, 0)
    base[0, 1] = base[0, 2] = FREE
    watch.update(20, [state("A", a, True), state("B", b)], base, reachable, 24)
    entry = watch.summary()[0]
    assert (entry["recovery_steps"], entry["recovery_steps_base"]) == (3, 10)


def test_unrecovered_knowledge_is_never() -> None:
    reachable = np.ones(SHAPE, dtype=bool)
    a, base = grid([(2, 3)]), grid([])
    watch = FailureWatch(["A"])
    watch.update(0, [state("A", a)], base, reachable, 24)
    watch.update(1, [state("A", a, True)], base, reachable, 24)
    watch.update(2, [state("A", a, True)], base, reachable, 24)
    entry = watch.summary()[0]
    assert entry["recovery_steps"] == entry["recovery_steps_base"] == "never"


def test_parts_that_leave_the_robot_talking_cost_no_knowledge() -> None:
    reachable = np.ones(SHAPE, dtype=bool)
    a, base = grid([(1, 1)]), grid([])
    watch = FailureWatch(["A"])
    watch.update(0, [state("A", a)], base, reachable, 24)
    watch.update(1, [state("A", a, False, "drive")], base, reachable, 24)
    watch.update(2, [state("A", a, False, "drive", "sensor")], base, reachable, 24)
    watch.update(3, [state("A", a, False, "drive", "sensor", "radio")], base, reachable, 24)
    watch.update(4, [state("A", a, True, "drive", "sensor", "radio")], base, reachable, 24)
    entries = watch.summary()
    assert [(e["step"], e["parts"], e["silenced"]) for e in entries] == [
        (1, ["drive"], False),
        (2, ["sensor"], False),
        (3, ["radio"], True),  # the radio silences it: its knowledge is counted here
        (4, ["robot"], False),  # already silent
    ]
    assert "knowledge_lost" not in entries[0]
    assert entries[2]["knowledge_lost"] == 1


def test_area_under_known_curves() -> None:
    ramp = [k / 10 for k in range(11)]
    assert normalised_area(ramp) == pytest.approx(0.5)
    assert normalised_area([1.0] * 5) == pytest.approx(1.0)
    assert normalised_area([0.0, 1.0, 1.0, 1.0, 1.0]) == pytest.approx(7 / 8)
    assert normalised_area([0.0, 1.0], steps=4) == pytest.approx(7 / 8)  # holds its last value
    assert normalised_area([0.4]) == 0.4


def far_failure(scenario_file: ScenarioFile, **changes: Any) -> Path:
    """Two robots in the two rooms of the rooms map, radios too short to reach each other
    or the base: B's map is its own when it fails at step 25 (by step 30 B has crossed
    into A's room and met it)."""
    data: dict[str, Any] = {
        "robots": [
            {"name": "A", "start": [8, 20], "heading_deg": 0},
            {"name": "B", "start": [70, 45], "heading_deg": 180},
        ],
        "steps": 70,
        "events": [{"step": 25, "fail": "B"}],
        "communication": {"model": "disk"},
        "team": {"speed": 2, "radius": 1.0, "sensor": {"range": 30}, "comm_range": 6},
        "base_station": {"position": [8, 30], "comm_range": 6},
    }
    return scenario_file(**(data | changes))


def test_knowledge_lost_in_a_run_equals_a_dense_count(scenario_file: ScenarioFile) -> None:
    sim = Simulation.from_yaml(far_failure(scenario_file))
    while sim.t < 25:
        sim.step()
    reach = sim.coverage.reachable
    a, b = (r.belief == FREE for r in sim.robots)
    base = sim.base.belief == FREE
    failure = sim.failures.failures[0]
    assert (failure.step, failure.robot) == (25, "B")
    assert failure.unreported == np.count_nonzero(b & reach & ~base)
    assert failure.knowledge_lost == np.count_nonzero(b & reach & ~base & ~a)
    assert failure.knowledge_lost > 0  # the test means something
    assert sim.record.robustness is None  # not a paired run: no columns


def run_cli(*args: str) -> int:
    return main(["run", *args, "--quiet", "--no-plots"])


def test_paired_run_baseline_equals_the_run_without_failures(
    scenario_file: ScenarioFile, tmp_path: Path
) -> None:
    path = far_failure(scenario_file, render={"final_png": False})
    assert run_cli(str(path), "--out", str(tmp_path / "paired"), "--paired") == 0
    report = json.loads((tmp_path / "paired" / "robustness.json").read_text())
    paired_summary = json.loads((tmp_path / "paired" / "summary.json").read_text())
    clean = far_failure(scenario_file, render={"final_png": False}, events=[])
    assert run_cli(str(clean), "--out", str(tmp_path / "clean")) == 0
    alone = json.loads((tmp_path / "clean" / "summary.json").read_text())
    baseline = report["baseline"]
    for key in ("steps_to_explored", "steps_to_known_at_base", "final_explored"):
        assert baseline[key] == alone[key]
    for key in ("auc_explored", "auc_known_at_base", "alive_fraction", "base_deficit_at_end"):
        assert baseline[key] == alone[key]
        assert report["run"][key] == paired_summary[key]
    assert baseline["steps"] == alone["steps"] and baseline["failures"] == 0
    assert report["run"]["alive_fraction"] == 0.5
    diff = report["difference"]
    assert diff["final_explored"] == pytest.approx(
        paired_summary["final_explored"] - alone["final_explored"]
    )
    for name in ("explored", "known_at_base"):
        key, sides = f"steps_to_{name}_0.9", [report[s][f"steps_to_{name}"]["0.9"] for s in SIDES]
        expected = None if None in sides else sides[0] - sides[1]
        assert diff[key] == expected
    header = (tmp_path / "paired" / "metrics.csv").read_text().splitlines()[0].split(",")
    assert header[-3:] == ["failures", "knowledge_lost", "lost_unrecovered"]
    assert "failures" not in (tmp_path / "clean" / "metrics.csv").read_text().splitlines()[0]


def test_a_paired_baseline_switches_off_the_faults_block_too(
    scenario_file: ScenarioFile, tmp_path: Path
) -> None:
    faults = {"random": [{"probability": 0.2, "robots": ["B"]}], "fail_if_out_of_contact_for": 500}
    path = far_failure(scenario_file, events=[], faults=faults, render={"final_png": False})
    assert run_cli(str(path), "--out", str(tmp_path / "paired"), "--paired") == 0
    report = json.loads((tmp_path / "paired" / "robustness.json").read_text())
    assert report["run"]["failures"] >= 1 and report["baseline"]["failures"] == 0
    clean = far_failure(scenario_file, events=[], render={"final_png": False})
    assert run_cli(str(clean), "--out", str(tmp_path / "clean")) == 0
    alone = json.loads((tmp_path / "clean" / "summary.json").read_text())
    assert report["baseline"]["auc_explored"] == alone["auc_explored"]
    assert report["baseline"]["steps"] == alone["steps"]


def test_replay_recomputes_the_robustness_columns(
    scenario_file: ScenarioFile, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = far_failure(scenario_file, simulation={"paired": True}, render={"final_png": False})
    out = tmp_path / "run"
    assert main(["run", str(path), "--out", str(out), "--no-plots"]) == 0
    assert f"baseline in {out / 'robustness.json'}" in capsys.readouterr().out
    assert main(["replay", str(out), "--metrics"]) == 0
    assert (out / "metrics.csv").read_bytes() == (out / "metrics-replayed.csv").read_bytes()
    rows = list(recompute_metrics(RunLog.open(out / "log")))
    assert rows[-1].robustness is not None and rows[-1].robustness[1] > 0


def test_paired_without_faults_is_a_clear_error(
    scenario_file: ScenarioFile, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = scenario_file(steps=5)
    assert run_cli(str(path), "--out", str(tmp_path / "out"), "--paired") == 2
    err = capsys.readouterr().err
    assert "no faults to switch off" in err and "Traceback" not in err
    assert err.count("\n") == 1  # one paragraph
    assert not (tmp_path / "out").exists()
    paired = scenario_file(steps=5, simulation={"paired": True})
    assert main(["validate", str(paired)]) == 2
    assert "no faults to switch off" in capsys.readouterr().err


def test_replayed_failure_views_equal_the_live_ones(
    scenario_file: ScenarioFile, tmp_path: Path
) -> None:
    path = far_failure(scenario_file, simulation={"presume_lost_after": 15})
    snaps, _, _ = record_run(path, tmp_path / "log", 70)
    for got, want in zip(RunLog.open(tmp_path / "log").snapshots(), snaps, strict=True):
        assert_same_snapshot(got, want)
    last = snaps[-1]
    assert last.failures == ((25, "B"),)
    assert last.lost_knowledge is not None and last.lost_knowledge.any()
    assert snaps[24].lost_knowledge is None  # step 24, before B fails
    assert any(a.features.get("lost") for a in last.agents)
    assert "lost" not in last.robots[1].features  # a failed robot presumes nothing


def test_failure_frames_replay_exactly(scenario_file: ScenarioFile, tmp_path: Path) -> None:
    path = far_failure(scenario_file, steps=85, simulation={"presume_lost_after": 15})
    out, flags = tmp_path / "run", ["--snapshot", "24,26,85", "--layers", "all"]
    assert run_cli(str(path), "--out", str(out), *flags) == 0
    assert main(["replay", str(out), *flags]) == 0
    frames = {}
    for step in (24, 26, 85):
        live = cv2.imread(str(out / f"step-{step:05d}.png"))
        assert np.array_equal(live, cv2.imread(str(out / f"replay-step-{step:05d}.png")))
        frames[step] = live
    red = [int(np.all(f[:60] == DEFAULT_STYLE.banner, axis=-1).sum()) for f in frames.values()]
    assert red[0] == 0 and red[1] > 1000 and red[2] == 0  # the banner line, for a while


def censoring_sim(steps: int, reached: int | None) -> SimpleNamespace:
    """A finished run as ``comparison`` reads it: steps, milestones, curves, record."""
    milestones = {"0.9": reached}
    return SimpleNamespace(
        record=SimpleNamespace(step=steps, explored=0.8, known_at_base=0.7),
        milestones=SimpleNamespace(explored=milestones, known_at_base=milestones),
        curves=SimpleNamespace(explored=[0.1] * steps, known_at_base=[0.1] * steps),
    )


def test_a_threshold_never_reached_has_no_difference_or_ratio() -> None:
    """A censored time is never turned into a number (the step cap + 1 was, before)."""
    never, reached = censoring_sim(400, None), censoring_sim(300, 120)
    report = comparison(never, reached)  # type: ignore[arg-type]
    for name in ("explored", "known_at_base"):
        key = f"steps_to_{name}_0.9"
        assert report["difference"][key] is None and report["ratio"][key] is None
        assert f"run: {key}" in report["never"]
    both = comparison(censoring_sim(400, 150), reached)  # type: ignore[arg-type]
    assert both["difference"]["steps_to_explored_0.9"] == 30 and not both["never"]
