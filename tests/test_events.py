"""Events are a plugin family: registered by YAML key, validated from the registry, applied
through a small context (fail a robot or one part, silence agents, log, own random stream)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import ClassVar

import numpy as np
import pytest
from pydantic import Field

from mresim_phys import Simulation
from mresim_phys.cli import main
from mresim_phys.errors import ScenarioError
from mresim_phys.plugin import Plugin
from mresim_phys.scenario.load import load_scenario
from mresim_phys.strategies import Decision
from mresim_phys.types import FREE
from mresim_phys.world.event_api import EventContext
from mresim_phys.world.event_catalog import EVENTS
from mresim_phys.world.event_params import EventParams

ScenarioFile = Callable[..., Path]


def test_built_in_events_are_registered_by_their_yaml_key() -> None:
    assert {"fail", "blackout"} <= set(EVENTS.names())
    for name in EVENTS.names():
        assert EVENTS.get(name).name == name
        assert issubclass(EVENTS.get(name).Params, EventParams)


def test_an_entry_without_a_known_event_key_names_the_known_ones(
    scenario_file: ScenarioFile, capsys: pytest.CaptureFixture[str]
) -> None:
    path = scenario_file(events=[{"step": 3, "explode": "A"}])
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err
    assert "events[0]" in err and "'fail'" in err and "'blackout'" in err
    assert "Traceback" not in err


def test_a_misspelt_event_field_is_an_error_with_a_hint(scenario_file: ScenarioFile) -> None:
    with pytest.raises(ScenarioError, match=r"events\[0\]\.untill.*did you mean 'until'"):
        load_scenario(scenario_file(events=[{"step": 3, "untill": 9, "blackout": ["A"]}]))


def test_a_part_failure_names_a_known_part(scenario_file: ScenarioFile) -> None:
    with pytest.raises(ScenarioError, match=r"events\[0\]\.part"):
        load_scenario(scenario_file(events=[{"step": 3, "fail": "A", "part": "wheel"}]))


def test_resolved_scenario_round_trips_its_events(scenario_file: ScenarioFile) -> None:
    events = [
        {"step": 3, "fail": "A", "part": "degraded", "speed_factor": 0.5, "range_factor": None},
        {"step": 4, "until": 9, "blackout": ["base", "B"], "channel": "main"},
    ]
    events[0] |= {"until": 7, "mode": None, "distance": None}
    scenario = load_scenario(scenario_file(events=events))
    dumped = scenario.model_dump(mode="json")["events"]
    assert dumped == events
    assert load_scenario(scenario_file(events=dumped)).events == scenario.events


def run(path: Path, steps: int) -> Simulation:
    sim = Simulation.from_yaml(path)
    for _ in range(steps):
        sim.step()
    return sim


def test_a_failed_drive_stops_motion_but_not_scans_or_radio(scenario_file: ScenarioFile) -> None:
    sim = run(scenario_file(events=[{"step": 2, "fail": "B", "part": "drive"}]), 2)
    robot = sim.robot("B")
    where = robot.position
    for _ in range(10):
        sim.step()
    assert robot.position == where and robot.alive and robot.state != "failed"
    assert sim.links[robot.index].any()  # still talks to A nearby


def test_a_failed_sensor_adds_nothing_to_the_map_but_the_robot_moves(
    scenario_file: ScenarioFile,
) -> None:
    silent = {"speed": 2, "radius": 1.0, "sensor": {"range": 30}, "comm_range": 0}
    path = scenario_file(
        events=[{"step": 1, "fail": "A", "part": "sensor"}],
        team=silent,
        base_station={"position": [8, 30], "comm_range": 0},
    )
    sim = run(path, 1)
    robot = sim.robot("A")
    known = np.count_nonzero(robot.belief == FREE)
    start = robot.position
    for _ in range(8):
        sim.step()
    assert robot.position != start and robot.alive
    assert np.count_nonzero(robot.belief == FREE) == known


def test_a_failed_radio_cuts_every_link_of_that_robot(scenario_file: ScenarioFile) -> None:
    sim = run(scenario_file(events=[{"step": 1, "fail": "B", "part": "radio"}]), 1)
    for _ in range(5):
        sim.step()
        assert not sim.links[sim.robot("B").index].any()
    assert sim.robot("B").alive


def test_events_at_step_zero_act_before_the_first_scan(scenario_file: ScenarioFile) -> None:
    sim = Simulation.from_yaml(scenario_file(events=[{"step": 0, "fail": "B"}]))
    assert sim.robot("B").state == "failed"
    assert sim.events_now == ["fail B"]
    assert sim.record.alive == 1


@pytest.mark.parametrize(
    ("part", "may_move", "may_scan"),
    [("robot", False, False), ("drive", False, True), ("sensor", True, False)],
)
def test_a_failure_at_step_zero_holds_from_the_first_scan_on(
    scenario_file: ScenarioFile, part: str, may_move: bool, may_scan: bool
) -> None:
    """Failed at step 0, B never moves (robot, drive) or never scans (robot, sensor)."""
    quiet = {"speed": 2, "radius": 1.0, "sensor": {"range": 30}, "comm_range": 0}
    path = scenario_file(
        events=[{"step": 0, "fail": "B", "part": part}],
        team=quiet,  # no radio: each robot's map holds only what it scanned itself
        base_station={"position": [8, 30], "comm_range": 0},
    )
    sim = Simulation.from_yaml(path)
    b, a = sim.robot("B"), sim.robot("A")
    start, a_start = b.position, a.position
    for _ in range(10):
        sim.step()
    if not may_move:
        assert b.position == start and b.distance == 0
    assert bool(np.any(b.belief == FREE)) == may_scan
    assert a.position != a_start and np.any(a.belief == FREE)  # the run itself goes on


def test_blackout_lines_are_logged_at_start_and_end(scenario_file: ScenarioFile) -> None:
    path = scenario_file(events=[{"step": 2, "until": 4, "blackout": ["A"], "channel": "main"}])
    sim = Simulation.from_yaml(path)
    lines = {}
    for _ in range(5):
        sim.step()
        lines[sim.t] = list(sim.events_now)
        if sim.t in (2, 3):
            assert not sim.links[sim.robot("A").index].any()
    assert lines[2] == ["blackout A (main) until 4"]
    assert lines[4] == ["blackout over A (main)"]


class CoinParams(EventParams):
    coin: str = Field(description="The robot the coin is flipped for.")


class CoinFlip(Plugin):
    """A third-party event: at its step, draw a number from its own stream and log it."""

    name = "coin"
    Params = CoinParams
    draws: ClassVar[list[float]] = []

    def apply(self, context: EventContext) -> None:
        if context.step == self.params.step:  # type: ignore[attr-defined]
            draw = float(context.rng.random())
            CoinFlip.draws.append(draw)
            context.log(f"coin {draw:.3f}")


def test_an_event_draws_only_from_its_own_named_stream(scenario_file: ScenarioFile) -> None:
    EVENTS.register(CoinFlip)
    try:
        for _ in range(2):
            path = scenario_file(events=[{"step": 2, "coin": "A"}], seed=11)
            run(path, 3)
        path = scenario_file(events=[{"step": 2, "coin": "A"}], seed=12)
        run(path, 3)
    finally:
        EVENTS._classes.pop("coin")
    assert CoinFlip.draws[0] == CoinFlip.draws[1] != CoinFlip.draws[2]


def test_a_cells_event_closes_a_door_for_rays_radio_and_the_explored_metric(
    scenario_file: ScenarioFile,
) -> None:
    """The rooms map's door is x 40..41, y 25..36; closing it cuts the line-of-sight link."""
    path = scenario_file(
        robots=[{"name": "A", "start": [30, 31]}, {"name": "B", "start": [52, 31]}],
        base_station={"position": [8, 30], "comm_range": 5},
        communication={"model": "line_of_sight"},
        events=[{"step": 2, "cells": [40, 25, 42, 37]}],
    )
    sim = Simulation.from_yaml(path)
    stay = {"A": Decision(), "B": Decision()}
    total = sim.coverage.total
    sim.step(actions=stay)
    assert sim.links[1, 2]
    sim.step(actions=stay)
    assert sim.events_now == ["cells [40, 25, 42, 37] walls"]
    assert sim.world.version == 1 and sim.world.occupied[25:37, 40:42].all()
    assert not sim.links[1, 2]
    assert sim.coverage.total == total - 24  # the 12 x 2 door cells left the free space
    scan_east = sim.world.cast_rays((30.0, 31.0), np.array([0.0]), 100.0, (0, 0xFFFFFFFF, 1))
    assert scan_east.ranges[0] == pytest.approx(10.0)  # the new wall face at x = 40


def test_a_cells_window_outside_the_map_is_a_clear_error(scenario_file: ScenarioFile) -> None:
    path = scenario_file(events=[{"step": 2, "cells": [70, 50, 90, 70]}])
    with pytest.raises(ScenarioError, match=r"events\[0\]\.cells.*80x60 map"):
        Simulation.from_yaml(path)


def test_a_decision_for_a_failed_robot_is_ignored_and_named(scenario_file: ScenarioFile) -> None:
    """``step(actions=...)`` for a robot that has failed moves nothing and says so."""
    sim = Simulation.from_yaml(scenario_file(events=[{"step": 1, "fail": "A"}]))
    sim.step()
    where = sim.robot("A").position
    go = Decision(path=np.array([[where[0] + 5.0, where[1]]]), goal=(where[0] + 5.0, where[1]))
    sim.step(actions={"A": go, "B": Decision()})
    assert sim.ignored_actions == ("A",)
    assert sim.robot("A").position == where
    sim.step(actions={"B": Decision()})
    assert sim.ignored_actions == ()
