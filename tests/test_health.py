"""Run health (knowledge/health.py, knowledge/frontier_reach.py, output/health.py): idle and
stuck steps, state changes with reasons, frontier cells a robot could reach, warnings; the
record in summary.json, the run log and its replay."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mresim_phys import Simulation
from mresim_phys.cli import main
from mresim_phys.knowledge import health
from mresim_phys.knowledge.activity import Health, health_of
from mresim_phys.knowledge.frontier_reach import frontier_check
from mresim_phys.knowledge.health import (
    CHECK_EVERY,
    FRUITLESS_AFTER,
    WARN_AFTER,
    WARN_FRUITLESS,
    HealthWatch,
    RobotStep,
)
from mresim_phys.output.health import replayed_health, run_health
from mresim_phys.output.runlog import RunLog
from mresim_phys.strategies import Decision
from mresim_phys.strategies.base import RobotView
from mresim_phys.strategies.relax import frontier_reachable
from mresim_phys.types import FREE, OCCUPIED, UNKNOWN

ScenarioFile = Callable[..., Path]
ONE_ROBOT = [{"name": "A", "start": [8, 20], "heading_deg": 0}]
QUITS = {"name": "health_plugins:QuitsAtFive", "params": {"replan_interval": 1}}


# --- which frontier cells a robot could reach ----------------------------------------------


def known_room(rows: int = 30, cols: int = 40) -> np.ndarray:
    """A belief: walls around, everything inside FREE."""
    belief = np.full((rows, cols), FREE, np.uint8)
    belief[0, :] = belief[-1, :] = belief[:, 0] = belief[:, -1] = OCCUPIED
    return belief


def test_a_frontier_counts_as_exploration_finds_it_and_specks_do_not() -> None:
    belief = known_room()
    belief[10, 20] = UNKNOWN  # its 8 neighbours form a frontier cluster
    assert frontier_check(belief, (5.5, 5.5), 1.0).frontier == 8
    belief = known_room()
    belief[1, 20] = UNKNOWN  # beside the wall: a cluster of its 5 free neighbours
    belief[20:23, 1:3] = OCCUPIED
    belief[21, 1:3] = UNKNOWN, FREE  # a notch: one free cell sees it, a speck
    assert frontier_check(belief, (5.5, 5.5), 1.0).frontier == 5


def test_frontier_cells_where_the_robot_has_been_do_not_count() -> None:
    belief = known_room()
    belief[10:14, 30:34] = UNKNOWN
    safe = np.zeros(belief.shape, dtype=bool)
    assert frontier_check(belief, (10.5, 10.5), 1.0, safe).reachable == 20
    safe[5:20, 25:40] = True  # it stood there and scanned: the hole stayed
    check = frontier_check(belief, (10.5, 10.5), 1.0, safe)
    assert (check.frontier, check.reachable, check.reason) == (0, 0, "none left")


def test_a_fully_known_room_has_none_left() -> None:
    check = frontier_check(known_room(), (10.5, 10.5), 2.0)
    assert (check.frontier, check.reachable, check.reason) == (0, 0, "none left")


def test_an_open_side_is_reachable() -> None:
    belief = known_room()
    belief[1:-1, 30:-1] = UNKNOWN  # the right part unknown: its edge is a frontier
    check = frontier_check(belief, (10.5, 10.5), 2.0)
    assert check.frontier == 28 and check.reachable == 28 and check.reason == "all reachable"


def test_cells_past_a_wall_are_behind_walls() -> None:
    belief = known_room()
    belief[:, 20] = OCCUPIED  # a wall splits the room
    belief[10:14, 30:34] = UNKNOWN  # a hole in the right half's knowledge
    check = frontier_check(belief, (10.5, 10.5), 1.0)
    assert check.frontier == 20 and check.reachable == 0 and check.behind_walls == 20
    assert check.reason == "behind walls"


def test_cells_past_a_gap_narrower_than_the_body_are_closed_by_clearance() -> None:
    belief = known_room()
    belief[:, 20] = OCCUPIED
    belief[15:17, 20] = FREE  # a two-cell gap
    belief[10:14, 30:34] = UNKNOWN
    narrow = frontier_check(belief, (10.5, 10.5), 2.0)  # a body of radius 2 does not pass
    assert narrow.reachable == 0 and narrow.closed_by_clearance == 20
    assert narrow.reason == "closed by clearance"
    small = frontier_check(belief, (10.5, 10.5), 0.5)
    assert small.reachable == 20 and small.reason == "all reachable"


def test_a_robot_with_no_room_for_its_body_reaches_nothing() -> None:
    belief = known_room(12, 12)
    belief[5, 5] = UNKNOWN
    check = frontier_check(belief, (5.5, 3.5), 8.0)  # no cell is 8 cells from every wall
    assert check.reachable == 0 and check.reason == "no room for its body where it stands"


# --- the watch, step by step ------------------------------------------------------------


def step(state: str = "active", distance: float = 0.0, path: bool = False, **kw: Any) -> RobotStep:
    values: dict[str, Any] = {"name": "A", "state": state, "distance": distance}
    values |= {"has_path": path, "can_move": True, "position": (10.5, 10.5), "radius": 1.0}
    values |= {"belief": known_room()} | kw
    return RobotStep(**values)


def test_activity_is_working_stuck_or_idle_from_the_odometer_and_path() -> None:
    watch = HealthWatch(["A"])
    steps = [
        step(),  # step 0: not assessed
        step(distance=1.0),  # moved: working
        step(distance=1.01, path=True),  # a path, no motion: stuck
        step("error", reason="collision at (1.0, 1.0)", distance=1.01),  # bumped: stuck
        step("active", reason="moved again", distance=1.02),  # parked: idle
        step(distance=1.02, can_move=False),  # drive broken: not assessed
    ]
    seen = []
    for n, robot in enumerate(steps):
        watch.update(n, [robot])
        seen.append(watch.view("A")[0])
    assert seen == ["", "working", "stuck", "stuck", "idle", ""]
    record = watch.report([steps[-1]]).summary()["robots"]["A"]
    assert (record["idle_steps"], record["stuck_steps"], record["longest_idle"]) == (1, 2, 1)
    assert [(c["from"], c["to"], c["reason"]) for c in record["state_changes"]] == [
        ("active", "error", "collision at (1.0, 1.0)"),
        ("error", "active", "moved again"),
    ]
    assert watch.view("base") == ("", None)


def test_done_counts_declarations_not_returns_after_a_bump() -> None:
    watch = HealthWatch(["A"])
    states = ["active", "done", "error", "done", "active", "done"]
    for n, state in enumerate(states):
        watch.update(n, [step(state, reason=f"r{n}")])
    assert watch.robots["A"].done_at == [1, 5]  # not 3: it was done before it bumped


def test_an_idle_robot_is_checked_when_it_stops_then_every_few_steps(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    calls: list[int] = []
    real = health.frontier_check
    watch = HealthWatch(["A"])

    def counted(*args: Any) -> Any:
        calls.append(watch.step or 0)
        return real(*args)

    monkeypatch.setattr(health, "frontier_check", counted)
    distance = 0.0
    for n in range(60):
        distance += 1.0 if n < 10 or 40 <= n < 45 else 0.0  # works, idles, works, idles
        watch.update(n, [step(distance=distance)])
    assert calls == [10, 10 + CHECK_EVERY, 45]


# --- whole runs ----------------------------------------------------------------------------


def test_a_parked_robot_with_frontiers_in_reach_counts_them_and_the_run_warns(
    scenario_file: ScenarioFile, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = scenario_file(robots=ONE_ROBOT, steps=40, team=parked_team())
    assert main(["run", str(path), "--out", str(tmp_path / "run"), "--quiet"]) == 0
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    record = summary["health"]["robots"]["A"]
    assert record["idle_steps"] == record["idle_with_frontier"] == 40
    assert record["first_idle_with_frontier"] == 1 and record["at_end"]["reachable_frontier_cells"]
    assert summary["health"]["robots_idle_with_frontier"] == 1
    assert summary["health"]["idle_robot_steps"] == 40
    [warning] = summary["health"]["warnings"]
    assert warning.startswith("robot A idled 40 steps (from step 1)")
    assert f"mresim: warning: {warning}\n" in capsys.readouterr().err


def test_a_robot_that_explored_everything_idles_without_a_warning(
    scenario_file: ScenarioFile, tmp_path: Path
) -> None:
    """A frontier robot in one closed room sees it whole, says it is done and parks: idle,
    but its map has no frontier left."""
    room = np.zeros((40, 50), bool)
    room[:2, :] = room[-2:, :] = room[:, :2] = room[:, -2:] = True
    image = tmp_path / "room.png"
    from PIL import Image

    Image.fromarray(np.where(room, 0, 255).astype(np.uint8)).save(image)
    team = {"speed": 2, "radius": 1.0, "sensor": {"range": 80, "fov_deg": 360, "rays": 720}}
    path = scenario_file(
        map={"image": str(image), "resolution": 0.1},
        team={**team, "comm_range": 20, "strategy": "frontier"},
        robots=[{"name": "A", "start": [20, 20], "heading_deg": 0}],
        stop={"all_done": False, "stalled_for": None},
        steps=40,
    )
    sim = Simulation.from_yaml(path)
    sim.run()
    record = run_health(sim)["health"]
    a = record["robots"]["A"]
    assert a["done_at"] and a["idle_steps"] >= 20  # parked at the base once done
    assert a["idle_with_frontier"] == 0 and a["at_end"]["reason"] == "none left"
    assert record["warnings"] == [] and record["robots_idle_with_frontier"] == 0


def test_state_change_reasons_are_logged_and_replayed_identically(
    scenario_file: ScenarioFile, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    robots = [
        {"name": "A", "start": [8, 20], "heading_deg": 0},
        {"name": "B", "start": [8, 40], "heading_deg": 0, "strategy": QUITS},
        {"name": "C", "start": [20, 30], "heading_deg": 90},
    ]
    events = [{"step": 10, "fail": "C"}]
    path = scenario_file(robots=robots, events=events, steps=30, stop={"all_done": False})
    out = tmp_path / "run"
    assert main(["run", str(path), "--out", str(out), "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    changes = {n: r["state_changes"] for n, r in summary["health"]["robots"].items()}
    assert changes["B"][0] == {"step": 5, "from": "active", "to": "done", "reason": "told to quit"}
    assert summary["health"]["robots"]["B"]["done_at"] == [5]
    assert changes["C"] == [{"step": 10, "from": "active", "to": "failed", "reason": "fail C"}]
    lines = [json.loads(line) for line in (out / "log" / "steps.jsonl").read_text().splitlines()]
    assert lines[5]["agents"][2]["health"] == "told to quit"
    assert lines[10]["agents"][3]["health"] == "fail C"
    assert "health" not in lines[6]["agents"][2]  # only where the state changed
    assert replayed_health(RunLog.open(out / "log")) == summary["health"]
    capsys.readouterr()
    assert main(["replay", str(out), "--metrics"]) == 0
    assert "health record recomputed: identical to" in capsys.readouterr().out


def test_replayed_activity_equals_the_live_one(scenario_file: ScenarioFile, tmp_path: Path) -> None:
    from mresim_phys.output.logwriter import RunLogWriter

    robots = [*ONE_ROBOT, {"name": "B", "start": [8, 40], "heading_deg": 0}]
    sim = Simulation.from_yaml(scenario_file(robots=robots, steps=25))
    live = []
    with RunLogWriter(tmp_path / "log", sim.snapshot(), name="tiny", seed=3) as writer:
        for n in range(25):
            actions = {"B": Decision()} if 8 <= n < 16 else None  # B parked for a while
            sim.step(actions)
            writer.write(sim.snapshot())
            live.append([health_of(r) for r in sim.snapshot().robots])
    replayed = [[health_of(r) for r in s.robots] for s in RunLog.open(tmp_path / "log").snapshots()]
    assert replayed[1:] == live
    assert Health("idle", None) in [b for _, b in live]


def test_a_log_without_reasons_replays_them_as_not_logged(
    scenario_file: ScenarioFile, tmp_path: Path
) -> None:
    path = scenario_file(robots=ONE_ROBOT, events=[{"step": 3, "fail": "A"}], steps=6)
    out = tmp_path / "run"
    assert main(["run", str(path), "--out", str(out), "--quiet"]) == 0
    steps = out / "log" / "steps.jsonl"
    lines = [json.loads(line) for line in steps.read_text().splitlines()]
    for line in lines:
        for agent in line["agents"]:
            agent.pop("health", None)
    steps.write_text("".join(json.dumps(line) + "\n" for line in lines))
    record = replayed_health(RunLog.open(out / "log"))
    assert record["robots"]["A"]["state_changes"][0]["reason"] == health.NOT_LOGGED


def parked_team() -> dict[str, Any]:
    team = {"speed": 2, "radius": 1.0, "sensor": {"range": 30}, "comm_range": 20}
    return {**team, "strategy": "health_plugins:Parked"}


# cluttered rooms where "within one cell of the body" (up to stop 49) called a frontier cell
# reachable that no strategy could take a target for: (seed, patches)
CLUTTERED = [(212, 160), (255, 160), (24, 250), (290, 250)]


@pytest.mark.parametrize(
    ("seed", "patches"), [(seed, 40) for seed in range(20)] + [*CLUTTERED, (7, 160), (8, 250)]
)
def test_a_frontier_health_calls_reachable_is_one_the_relaxed_strategy_finds(
    seed: int, patches: int
) -> None:
    """Health's 'idle with reachable frontier cells' accuses a robot only when its strategy,
    relaxed to its body radius, would find a frontier target, and every time it would: on
    random rooms of walls and unknown patches the two answers agree."""
    rng = np.random.default_rng(seed)
    belief = known_room(40, 50)
    for _ in range(patches):  # walls and unknown patches of random size and place
        r, c = rng.integers(1, 38), rng.integers(1, 48)
        h, w = rng.integers(1, 4), rng.integers(1, 4)
        belief[r : r + h, c : c + w] = OCCUPIED if rng.random() < 0.5 else UNKNOWN
    free = np.argwhere(belief == FREE)
    radius = float(rng.choice([0.5, 1.0, 1.5]))
    for row, col in free[rng.choice(len(free), 10, replace=False)]:
        position = (col + 0.5, row + 0.5)
        view = RobotView(
            step=10, name="A", position=position, heading=0.0, belief=belief, radius=radius,
            clearance=radius + 0.5, speed=2.0, sensor_range=30.0, role="explorer",
            base_position=position, teammates={}, rng=np.random.default_rng(0),
        )  # fmt: skip
        reachable = frontier_check(belief, position, radius).reachable > 0
        assert reachable == frontier_reachable(view, radius)


def test_frontier_cells_the_strategy_gave_up_do_not_count() -> None:
    """Cells tried from two spots in vain (``strategies/giveup.py``) are left out before
    clustering, as the strategy leaves them: what remains of their cluster is a speck."""
    belief = known_room()
    belief[10:14, 30:34] = UNKNOWN  # a hole: a 20-cell frontier ring
    given_up = np.zeros(belief.shape, dtype=bool)
    assert frontier_check(belief, (10.5, 10.5), 1.0, None, given_up).reachable == 20
    given_up[9:15, 29:35] = True
    given_up[9, 29:31] = False  # two cells left: below the smallest cluster
    check = frontier_check(belief, (10.5, 10.5), 1.0, None, given_up)
    assert (check.frontier, check.reason) == (0, "none left")


def test_given_up_cells_travel_through_the_run_log(
    scenario_file: ScenarioFile, tmp_path: Path
) -> None:
    """The health record replayed from a log leaves out the same given-up cells as the
    live run: the strategy's given_up grid is logged with each robot."""
    from mresim_phys.output.logwriter import RunLogWriter
    from mresim_phys.strategies.giveup import Tried

    sim = Simulation.from_yaml(scenario_file(robots=ONE_ROBOT, steps=12))
    live = []
    with RunLogWriter(tmp_path / "log", sim.snapshot(), name="tiny", seed=3) as writer:
        for n in range(12):
            sim.step()
            if n == 4:  # as if A had tried a frontier from two spots in vain
                strategy = sim.robots[0].strategy
                tried = Tried.empty(sim.robots[0].belief.shape)
                rows, cols = np.mgrid[20:30, 50:60]
                tried.give_up(rows.ravel(), cols.ravel())
                strategy._tried = tried  # type: ignore[union-attr]
            writer.write(sim.snapshot())
            live.append(sim.snapshot().robots[0].given_up)
    replayed = [s.robots[0].given_up for s in RunLog.open(tmp_path / "log").snapshots()][1:]
    assert all(g is None for g in live[:4]) and all(g is None for g in replayed[:4])
    for got, expected in zip(replayed[4:], live[4:], strict=True):
        assert got is not None and expected is not None
        assert np.array_equal(got, expected) and int(got.sum()) == 100


def test_a_robot_its_strategy_holds_still_waits_and_is_never_warned_about() -> None:
    """A relay at its meeting point (its decision's goal is where it stands) waits: that is
    neither idle nor stuck, however much frontier its map holds; once done it idles."""
    belief = known_room()
    belief[5:10, 30:35] = UNKNOWN  # reachable frontier in its map all along
    watch = HealthWatch(["A"])
    held = {"belief": belief, "goal": (10.5, 10.5)}
    for n in range(WARN_AFTER + 5):
        watch.update(n, [step(**held)])
    assert watch.view("A")[0] == "waiting"
    report = watch.report([step(**held)])
    record = report.summary()["robots"]["A"]
    assert record["waiting_steps"] == WARN_AFTER + 4 and record["idle_steps"] == 0
    assert record["idle_with_frontier"] == 0 and report.warnings == []
    assert report.totals()["waiting_robot_steps"] == WARN_AFTER + 4
    watch.update(WARN_AFTER + 5, [step("done", reason="mission complete", **held)])
    assert watch.view("A")[0] == "idle"
    watch.update(WARN_AFTER + 6, [step(belief=belief, goal=(20.5, 10.5))])
    assert watch.view("A")[0] == "idle"  # a goal elsewhere and no path: no plan, idle


def test_relays_that_wait_for_their_partners_raise_no_warning() -> None:
    """The shipped leader-follower run: its relays hold at the edge of their parents'
    range for hundreds of steps while their maps hold frontier; before relays were told
    apart, both warned (``robot R1 idled 178 steps``). (Its leader may still warn: done
    once no frontier lies within the chain's reach, it parks with frontier beyond it.)"""
    sim = Simulation.from_yaml(
        Path(__file__).parent.parent / "scenarios" / "22_rooms_leader_follower.yaml"
    )
    sim.run()
    record = run_health(sim)["health"]
    for relay in ("R1", "R2"):
        counts = record["robots"][relay]
        assert counts["idle_with_frontier"] == counts["idle_steps"] == 0
        assert counts["waiting_steps"] >= 200
        assert not any(w.startswith(f"robot {relay} ") for w in record["warnings"])


# --- fruitless work: working while the team makes no progress ----------------------------


def test_a_robot_working_while_the_team_gains_nothing_is_fruitless_and_warned_about() -> None:
    """Moving every step, the team's fractions flat: from FRUITLESS_AFTER steps on each
    step is fruitless; a waiting or done robot never is; progress stops the count."""
    watch = HealthWatch(["A", "B", "C"])
    last = FRUITLESS_AFTER + WARN_FRUITLESS + 9
    for n in range(last + 1):
        robots = [
            step(distance=float(n)),  # works every step
            RobotStep(**{**step(goal=(10.5, 10.5)).__dict__, "name": "B"}),  # waits
            RobotStep(**{**step("done", distance=float(n)).__dict__, "name": "C"}),  # going home
        ]
        watch.update(n, robots)
        watch.note_progress(n, 0.5 if n >= 5 else 0.1, 0.2)  # progress up to step 5
    report = watch.report(robots)
    a = report.summary()["robots"]["A"]
    assert a["first_fruitless"] == 5 + FRUITLESS_AFTER
    assert a["fruitless_steps"] == last - (5 + FRUITLESS_AFTER) + 1
    assert [r["fruitless_steps"] for n, r in report.summary()["robots"].items() if n != "A"] == [
        0,
        0,
    ]
    assert report.totals()["robots_fruitless"] == 1
    assert report.totals()["fruitless_robot_steps"] == a["fruitless_steps"]
    warned = [w for w in report.warnings if w.startswith("robot A worked")]
    assert len(warned) == 1 and f"from step {5 + FRUITLESS_AFTER}" in warned[0]
    watch.note_progress(last + 1, 0.6, 0.2)  # the team gains again: no more counted
    watch.update(last + 2, [step(distance=float(last + 2))])
    watch.note_progress(last + 2, 0.6, 0.2)
    assert watch.robots["A"].fruitless == a["fruitless_steps"]


def test_a_shuttling_robot_is_flagged_live_and_in_the_replay(
    scenario_file: ScenarioFile, tmp_path: Path
) -> None:
    """A robot driving back and forth for ever never idles: only the fruitless count and
    its warning show it, in summary.json and recomputed from the run log alike."""
    steps = FRUITLESS_AFTER + WARN_FRUITLESS + 40
    shuttle = {"name": "health_plugins:Shuttles", "params": {"replan_interval": 4}}
    path = scenario_file(
        robots=[{**ONE_ROBOT[0], "strategy": shuttle}],
        stop={"all_done": False, "stalled_for": None},
        steps=steps,
    )
    out = tmp_path / "run"
    assert main(["run", str(path), "--out", str(out), "--quiet"]) == 0
    record = json.loads((out / "summary.json").read_text())["health"]
    a = record["robots"]["A"]
    assert a["idle_steps"] == 0 and a["fruitless_steps"] >= WARN_FRUITLESS
    assert record["robots_fruitless"] == 1
    assert any(w.startswith("robot A worked") for w in record["warnings"])
    assert replayed_health(RunLog.open(out / "log")) == record
    last = list(RunLog.open(out / "log").snapshots())[-1]
    assert health_of(last.robots[0]).activity == "fruitless"  # drawn and labelled so on frames
