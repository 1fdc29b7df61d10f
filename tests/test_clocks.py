"""Robots with their own clocks (``clocks/``): a decision period bounds how often a strategy
is asked, a compute delay holds a plan back, a slow platform acts only on its steps, a scan
period spaces scans; failures, recoveries and a caller's decisions respect them; the run is
the same bytes in any process and its replay equals it."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from test_dynamic_render import assert_replay_equals_live

from mresim_phys import Simulation
from mresim_phys.agents import Robot
from mresim_phys.cli import main
from mresim_phys.clocks.feature import CLOCK, Clock
from mresim_phys.columns import value_of
from mresim_phys.strategies import Decision

SCENARIOS = Path(__file__).resolve().parent.parent / "scenarios"
OFFICE = SCENARIOS / "02_office_frontier.yaml"
MIXED = SCENARIOS / "32_office_mixed_clocks.yaml"


def record_asks(robot: Robot, sim: Simulation) -> list[tuple[int, Decision, bool]]:
    """Wrap the robot's strategy: every ask as (step, decision, whether the robot stood
    with no path when asked and the decision sends it away from where it stood)."""
    asks: list[tuple[int, Decision, bool]] = []
    strategy: Any = robot.strategy
    decide = strategy.decide

    def counted(view: Any) -> Decision:
        decision: Decision = decide(view)
        path, (x, y) = decision.path, robot.position
        away = len(path) > 0 and bool((np.hypot(path[:, 0] - x, path[:, 1] - y) > 0.1).any())
        asks.append((sim.t, decision, len(robot.path) == 0 and away))
        return decision

    strategy.decide = counted
    return asks


def clock_of(robot: Robot) -> Clock:
    clock = CLOCK.state_of(robot.features)
    assert clock is not None
    return clock


def office(**clock: Any) -> Simulation:
    return Simulation.from_yaml(OFFICE, steps=120, **{"team.clock": clock})


@pytest.mark.parametrize("period", [3, 7])
def test_a_robot_with_decision_period_k_is_asked_at_most_every_k_steps(period: int) -> None:
    sim = office(decision_period=period)
    asks = [record_asks(r, sim) for r in sim.robots]
    sim.run()
    for robot, robot_asks in zip(sim.robots, asks, strict=True):
        steps = [t for t, _, _ in robot_asks]
        assert len(steps) >= 5  # it did decide, more than once
        assert min(np.diff(steps)) >= period
        assert len(steps) <= math.ceil(sim.t / period) + 1  # + the ask of step 1
        assert clock_of(robot).decisions == len(steps)
    free = office()  # without a period the same robots replan more often
    free_asks = [record_asks(r, free) for r in free.robots]
    free.run()
    assert sum(map(len, free_asks)) > sum(map(len, asks))


@pytest.mark.parametrize("delay", [1, 3])
def test_a_compute_delay_d_makes_a_new_plan_move_the_robot_d_steps_later(delay: int) -> None:
    sim = office(compute_delay=delay)
    robot = sim.robot("A")
    asks = record_asks(robot, sim)
    # id of the decision followed -> (first step it was, the decision: held so that no
    # later decision can reuse a collected one's id)
    adopted: dict[int, tuple[int, Decision]] = {}
    odometer = [robot.distance]
    for _ in range(100):
        sim.step()
        if robot.decision is not None:
            adopted.setdefault(id(robot.decision), (sim.t, robot.decision))
        odometer.append(robot.distance)
    standing = [(t, d) for t, d, stood in asks if stood and t + delay <= sim.t]
    assert len(standing) >= 3
    for t, decision in standing:
        assert adopted[id(decision)] == (t + delay, decision)
        assert all(odometer[s] == odometer[t] for s in range(t, t + delay))  # stood still
        assert odometer[t + delay] > odometer[t + delay - 1]  # first move: d steps later


@pytest.mark.parametrize(("every", "phase"), [(2, 0), (3, 1)])
def test_a_slow_platform_moves_decides_and_scans_only_on_its_steps(every: int, phase: int) -> None:
    sim = Simulation.from_yaml(
        OFFICE, steps=60, robots={"B": {"clock": {"act_every": every, "phase": phase}}}
    )
    slow, quick = sim.robot("B"), sim.robot("A")
    asks = record_asks(slow, sim)
    moves, scans, quick_moves = [], [], 0
    for _ in range(60):
        before, scanned, quick_before = slow.distance, slow.scans, quick.distance
        sim.step()
        if slow.distance > before:
            moves.append(sim.t)
        if slow.scans > scanned:
            scans.append(sim.t)
        quick_moves += quick.distance > quick_before
    assert len(moves) >= 60 // every - 2 and quick_moves >= 55
    assert all(t % every == phase for t in moves + scans + [t for t, _, _ in asks])


def test_a_robot_off_its_step_still_communicates() -> None:
    sim = Simulation.from_yaml(OFFICE, steps=20, **{"team.clock": {"act_every": 5}})
    for _ in range(7):
        sim.step()
        if sim.t % 5:
            assert sim.links[0].any()  # the base hears the team on steps no robot acts on


def test_a_scan_period_spaces_the_steps_a_robot_scans_on() -> None:
    sim = office(scan_period=3)
    robot = sim.robot("C")
    steps = []
    for _ in range(60):
        scanned = robot.scans
        sim.step()
        if robot.scans > scanned:
            steps.append(sim.t)
    assert len(steps) >= 15 and min(np.diff([0, *steps])) >= 3


def test_a_failure_drops_the_pending_plan_and_a_recovery_restarts_the_clock(
    scenario_file: Callable[..., Path],
) -> None:
    team = {"speed": 2, "radius": 1.0, "sensor": {"range": 30}, "comm_range": 20}
    team["clock"] = {"act_every": 3, "compute_delay": 5}
    path = scenario_file(team=team, events=[{"step": 5, "fail": "B", "until": 17}])
    sim = Simulation.from_yaml(path)
    b = sim.robot("B")
    clock = clock_of(b)
    while sim.t < 4:
        sim.step()
    assert clock_of(b).pending is not None  # B waits for the plan it asked for on step 3
    sim.step()
    assert not b.alive and clock_of(b).pending is None and not clock_of(b).acting
    while sim.t < 17:
        sim.step()
    assert (
        sim.robot("B").alive and clock_of(b).acting and clock.origin == 17
    )  # it acts on 17, 20, 23, ...
    acting = []
    for _ in range(6):
        sim.step()
        acting.append(clock.acting)
    assert acting == [False, False, True, False, False, True]


def test_a_callers_decision_waits_for_the_robots_next_step() -> None:
    sim = Simulation.from_yaml(OFFICE, steps=30, robots={"A": {"clock": {"act_every": 4}}})
    robot = sim.robot("A")
    sim.step()  # step 1: A does not act (it acts on 4, 8, ...)
    go = Decision(path=np.array([[60.0, 300.0], [80.0, 300.0]]), goal=(80.0, 300.0))
    sim.step({"A": go})  # step 2
    assert robot.decision is not go
    sim.step()  # step 3
    assert robot.decision is not go
    before = robot.distance
    sim.step()  # step 4: A acts, and follows the decision it was given
    assert robot.decision is go and robot.distance > before


def test_a_robot_its_clock_holds_still_is_waiting_not_idle() -> None:
    sim = Simulation.from_yaml(OFFICE, steps=80, **{"team.clock": {"act_every": 2}})
    sim.run()
    for name in ("A", "B", "C", "D"):
        health = sim.health.robots[name]
        assert health.waiting >= 35 and health.idle <= 5, (name, health)


def test_the_decisions_column_counts_every_ask(tmp_path: Path) -> None:
    out = tmp_path / "run"
    assert (
        main(["run", str(MIXED), "--out", str(out), "--quiet", "--no-plots", "--steps", "40"]) == 0
    )
    lines = (out / "metrics.csv").read_text().splitlines()
    header, last = lines[0].split(","), lines[-1].split(",")
    sim = Simulation.from_yaml(MIXED, steps=40)
    sim.run()
    total = sum(clock_of(r).decisions for r in sim.robots if CLOCK.key in r.features)
    assert int(last[header.index("decisions")]) == total > 0


def test_same_seed_same_bytes_with_and_without_threads(tmp_path: Path) -> None:
    outs = []
    for threads in ("1", "2"):
        out = tmp_path / f"run{threads}"
        args = ["run", str(MIXED), "--out", str(out), "--quiet", "--no-plots", "--steps", "60"]
        assert main([*args, "--threads", threads]) == 0
        outs.append(
            ((out / "metrics.csv").read_bytes(), (out / "log" / "steps.jsonl").read_bytes())
        )
    assert outs[0] == outs[1]


def test_a_drawn_delay_varies_with_the_seed_and_only_with_it() -> None:
    def delays(seed: int) -> list[int]:
        sim = Simulation.from_yaml(
            OFFICE, seed=seed, steps=60, **{"team.clock": {"compute_delay": {"min": 0, "max": 4}}}
        )
        robot = sim.robot("A")
        waits = []
        for _ in range(60):
            sim.step()
            value = CLOCK.value_in(robot.features)
            assert value is not None
            waits.append(value.wait)
        return waits

    assert delays(7) == delays(7) != delays(8)
    assert max(delays(7)) <= 4


def test_the_mixed_clock_team_replays_as_live(tmp_path: Path) -> None:
    data = yaml.safe_load(MIXED.read_text())
    data["steps"] = 45
    data["map"]["image"] = str((MIXED.parent / data["map"]["image"]).resolve())
    short = tmp_path / "mixed.yaml"
    short.write_text(yaml.safe_dump(data, sort_keys=False))
    assert_replay_equals_live(short, tmp_path / "run", (5, 12, 30, 45))


@pytest.mark.parametrize(
    ("clock", "field"),
    [
        ({"decision_period": 0}, "clock.decision_period"),
        ({"act_every": 0}, "clock.act_every"),
        ({"act_every": 2, "phase": 2}, "phase 2 is not below act_every 2"),
        ({"compute_delay": -1}, "clock.compute_delay"),
        ({"compute_delay": {"min": 3, "max": 1}}, "below its min"),
        ({"scan_period": 0.5}, "clock.scan_period"),
        ({"period": 3}, "clock.period"),
    ],
)
def test_bad_clock_input_is_one_paragraph_naming_the_field_and_exit_2(
    scenario_file: Callable[..., Path], capsys: pytest.CaptureFixture[str], clock: Any, field: str
) -> None:
    team = {"speed": 2, "radius": 1.0, "sensor": {"range": 30}, "clock": clock}
    assert main(["validate", str(scenario_file(team=team))]) == 2
    err = capsys.readouterr().err
    assert field in err and "Traceback" not in err and "scenario.yaml" in err


def test_rendezvous_pairs_still_agree_when_their_plans_come_late() -> None:
    """A plan that waited is followed, and its proposal sent, for a step before its
    strategy decides again: role_based's pairs still agree and keep their meetings."""
    rooms = SCENARIOS / "23_rooms_role_based.yaml"
    sim = Simulation.from_yaml(rooms, **{"team.clock": {"compute_delay": 3}})
    sim.run()
    kept = value_of("meetings_kept", sim.record)
    assert isinstance(kept, int) and kept >= 3
    assert sim.stop_reason() == "known_at_base"
