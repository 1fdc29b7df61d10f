"""Overrides merge deeply: team overrides beat robots' own fields; robots by name; dotted keys."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from mresim_phys import Simulation
from mresim_phys.errors import ScenarioError
from mresim_phys.scenario.load import load_scenario
from mresim_phys.scenario.overrides import apply_overrides, deep_merge

ScenarioFile = Callable[..., Path]


def test_team_override_beats_a_robots_own_field(scenario_file: ScenarioFile) -> None:
    scenario = load_scenario(scenario_file(), team={"speed": 4})  # robot B sets speed 3 itself
    assert [r.speed for r in scenario.robots] == [4.0, 4.0]
    assert scenario.team.speed == 4.0


def test_nested_team_override_keeps_the_other_nested_fields(scenario_file: ScenarioFile) -> None:
    scenario = load_scenario(scenario_file(), team={"sensor": {"rays": 91}})
    for robot in scenario.robots:
        assert robot.sensor.rays == 91 and robot.sensor.range == 30.0


def test_robots_by_name_and_dotted_keys(scenario_file: ScenarioFile) -> None:
    scenario = load_scenario(
        scenario_file(), robots={"B": {"sensor": {"range": 12}}}, **{"stop.explored": 0.5}
    )
    assert [r.sensor.range for r in scenario.robots] == [30.0, 12.0]
    assert scenario.stop.explored == 0.5 and scenario.stop.all_done is True


def test_an_override_for_a_robot_the_team_lacks_is_a_clear_error(
    scenario_file: ScenarioFile,
) -> None:
    with pytest.raises(ScenarioError, match=r"robots \['Z'\].*\['A', 'B'\]"):
        load_scenario(scenario_file(), robots={"Z": {"speed": 1}})


def test_simulation_from_yaml_takes_deep_overrides(scenario_file: ScenarioFile) -> None:
    sim = Simulation.from_yaml(scenario_file(), team={"radius": 0.5}, seed=9)
    assert [r.radius for r in sim.robots] == [0.5, 0.5] and sim.scenario.seed == 9


def test_merge_rules() -> None:
    assert deep_merge({"a": [1, 2]}, {"a": [3]}) == {"a": [3]}  # lists replace
    assert deep_merge({"a": 1}, None) == {"a": 1}  # None leaves as is
    data = {"robots": [{"name": "A", "speed": 2}], "team": {}}
    out = apply_overrides(data, {"robots": [{"name": "C"}]})
    assert out["robots"] == [{"name": "C"}]  # a list replaces the team
    assert data["robots"] == [{"name": "A", "speed": 2}]  # the input is not changed
