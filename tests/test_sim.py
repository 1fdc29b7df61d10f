"""The simulation cycle: determinism, simultaneity, motion limits, failures, metrics."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from conftest import csv_row

from mresim_phys import Simulation
from mresim_phys.scenario.load import load_scenario
from mresim_phys.types import FREE, UNKNOWN

ScenarioFile = Callable[..., Path]


def rollout(path: Path, steps: int, **overrides: object) -> tuple[list[list[str]], Simulation]:
    sim = Simulation.from_yaml(path, steps=steps, **overrides)
    rows = [csv_row(record) for record in sim.iterate()]
    return rows, sim


def test_same_seed_same_run(scenario_file: ScenarioFile) -> None:
    path = scenario_file(
        team={
            "speed": 2,
            "radius": 1.0,
            "sensor": {"range": 30, "noise_std": 0.3},
            "comm_range": 20,
            "strategy": "random_walk",
        }
    )
    first, sim_a = rollout(path, 40)
    second, sim_b = rollout(path, 40)
    assert first == second
    for a, b in zip(sim_a.robots, sim_b.robots, strict=True):
        assert np.array_equal(a.belief, b.belief)


def test_different_seed_changes_a_random_run(scenario_file: ScenarioFile) -> None:
    path = scenario_file(
        team={
            "speed": 2,
            "radius": 1.0,
            "sensor": {"range": 30},
            "comm_range": 20,
            "strategy": "random_walk",
        }
    )
    assert rollout(path, 30, seed=1)[0] != rollout(path, 30, seed=2)[0]


def test_robot_order_never_changes_the_result(scenario_file: ScenarioFile) -> None:
    """Robots act as if simultaneously: listing them in another order gives the same run."""
    robots = [
        {"name": "A", "start": [8, 20], "heading_deg": 0},
        {"name": "B", "start": [8, 40], "heading_deg": 0, "speed": 3},
        {"name": "C", "start": [20, 30], "heading_deg": 90},
    ]
    forward = rollout(scenario_file(robots=robots), 40)[1]
    backward = rollout(scenario_file(robots=robots[::-1]), 40)[1]
    for robot in forward.robots:
        other = backward.robot(robot.name)
        assert robot.position == other.position
        assert robot.distance == other.distance
        assert np.array_equal(robot.belief, other.belief)
    assert forward.record.explored == backward.record.explored


def test_robots_move_at_most_their_speed_and_never_into_walls(scenario_file: ScenarioFile) -> None:
    sim = Simulation.from_yaml(scenario_file(), steps=60)
    truth = sim.world.occupied
    before = {r.name: r.position for r in sim.robots}
    for _ in range(60):
        sim.step()
        for robot in sim.robots:
            x, y = robot.position
            moved = math.dist(before[robot.name], robot.position)
            assert moved <= robot.speed + 1e-9
            assert not sim.world.overlaps_wall(robot.position, robot.radius * 0.999)
            assert not truth[int(y), int(x)]
            before[robot.name] = robot.position


def test_exploration_progresses_and_metrics_are_monotone_fractions(
    scenario_file: ScenarioFile,
) -> None:
    rows, _ = rollout(scenario_file(steps=80), 80)
    explored = [float(r[1]) for r in rows]
    at_base = [float(r[2]) for r in rows]
    assert explored == sorted(explored) and at_base == sorted(at_base)
    assert all(0 <= v <= 1 for v in explored + at_base)
    assert explored[-1] > 0.8
    assert at_base[-1] <= explored[-1] + 1e-12


def test_strategies_never_see_the_truth(scenario_file: ScenarioFile) -> None:
    """A robot's grid holds only what it sensed or was told: unknown beyond its view at start."""
    sim = Simulation.from_yaml(scenario_file(), steps=1)
    for robot in sim.robots:
        view = sim.view_of(robot)
        assert not view.belief.flags.writeable
        assert np.count_nonzero(view.belief == UNKNOWN) > 0.3 * view.belief.size
        assert not hasattr(view, "truth") and not hasattr(view, "world")


def test_a_failed_robot_stops_moving_sensing_and_sharing(scenario_file: ScenarioFile) -> None:
    path = scenario_file(events=[{"step": 5, "fail": "B"}], steps=60)
    sim = Simulation.from_yaml(path)
    for _ in range(5):
        sim.step()
    failed = sim.robot("B")
    frozen_at, frozen_map = failed.position, failed.belief.copy()
    heard = {name: info.step for name, info in sim.robot("A").teammates.items()}
    for _ in range(40):
        sim.step()
    assert failed.state == "failed" and failed.position == frozen_at
    assert np.array_equal(failed.belief, frozen_map)
    assert sim.robot("A").teammates["B"].step == heard["B"] <= 5
    assert sim.record.alive == 1
    assert not sim.links[failed.index].any()


def test_base_knows_only_what_reached_it(scenario_file: ScenarioFile) -> None:
    """With a zero comm range nothing reaches the base, however much is explored."""
    path = scenario_file(
        base_station={"position": [8, 30], "comm_range": 0},
        team={"speed": 2, "radius": 1.0, "sensor": {"range": 30}, "comm_range": 0},
    )
    rows, sim = rollout(path, 30)
    assert float(rows[-1][1]) > 0.2
    assert float(rows[-1][2]) == 0.0
    assert not (sim.base.belief == FREE).any()


def test_one_scan_per_step_mode_scans_less_but_still_explores(scenario_file: ScenarioFile) -> None:
    path = scenario_file(simulation={"scan": "step"}, steps=40)
    sim = Simulation.from_yaml(path)
    sim.run()
    assert sim.record.explored > 0.3


def test_stop_rule_ends_the_run_early(scenario_file: ScenarioFile) -> None:
    sim = Simulation.from_yaml(scenario_file(stop={"explored": 0.3}, steps=500))
    last = sim.run()
    assert last.explored >= 0.3 and last.step < 500
    assert sim.stop_reason() == "explored"


def test_scenario_and_seed_override(scenario_file: ScenarioFile) -> None:
    scenario = load_scenario(scenario_file(), seed=9, steps=4)
    assert (scenario.seed, scenario.steps) == (9, 4)
    with pytest.raises(StopIteration):
        iterator = Simulation(scenario).iterate()
        for _ in range(10):
            next(iterator)


def test_a_stalled_run_stops_with_reason_stalled(scenario_file: ScenarioFile) -> None:
    """Robots that can no longer move make no progress: the run ends N steps after the last gain."""
    stuck = [{"step": 1, "fail": name, "part": "drive"} for name in ("A", "B")]
    sim = Simulation.from_yaml(
        scenario_file(steps=500, events=stuck, stop={"stalled_for": 25, "all_done": True})
    )
    last = sim.run()
    assert sim.stop_reason() == "stalled"
    assert last.step == sim.stall.last_progress + 25 and last.step < 60
    endless = Simulation.from_yaml(
        scenario_file(steps=80, events=stuck, stop={"stalled_for": None, "all_done": True})
    )
    assert endless.run().step == 80 and endless.stop_reason() == "steps"


def test_slow_steady_gains_count_as_progress() -> None:
    from mresim_phys.tracking import StallWatch

    watch = StallWatch(window=5, gain=0.001)
    for step in range(40):  # 0.0004 a step: a gain of 0.001 every three steps
        watch.update(_Fractions(step, 0.0004 * step, 0.0))
        assert not watch.stalled(step)
    for step in range(40, 46):  # no more gain
        watch.update(_Fractions(step, 0.0004 * 39, 0.0))
    assert watch.stalled(45) and watch.last_progress <= 39


def test_a_robot_first_done_restarts_the_stall_clock_once() -> None:
    """A robot that sets out home with its map is progress the fractions do not show yet
    (RAS2014-2: the run stopped stalled while the robots drove home, the base at 6 %)."""
    from mresim_phys.tracking import StallWatch

    watch = StallWatch(window=5, gain=0.001)
    watch.update(_Fractions(0, 0.5, 0.1))
    for step in range(1, 4):
        watch.update(_Fractions(step, 0.5, 0.1))
    watch.update(_Fractions(4, 0.5, 0.1, done=("A",)))
    assert watch.last_progress == 4 and not watch.stalled(8)
    for step in range(5, 10):  # A stays done: no news
        watch.update(_Fractions(step, 0.5, 0.1, done=("A",)))
    assert watch.stalled(9)
    watch.update(_Fractions(10, 0.5, 0.1, done=("A", "B")))
    assert watch.last_progress == 10
    watch.update(_Fractions(11, 0.5, 0.1))  # both back at work
    watch.update(_Fractions(12, 0.5, 0.1, done=("A", "B")))  # done again: counted once
    assert watch.last_progress == 10 and watch.stalled(15)


class _Fractions:
    """The part of a step record that StallWatch reads."""

    def __init__(
        self, step: int, explored: float, known_at_base: float, done: tuple[str, ...] = ()
    ) -> None:
        self.step, self.explored, self.known_at_base = step, explored, known_at_base
        self.robots = tuple(SimpleNamespace(name=name, state="done") for name in done)
