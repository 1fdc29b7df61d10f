"""Scenario loading contract: YAML -> validated Scenario, and every mistake's message."""

from __future__ import annotations

import re
import sys
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
import yaml

from mresim_phys.errors import MapError, ScenarioError
from mresim_phys.scenario.load import load_scenario
from mresim_phys.scenario.schema import Scenario
from mresim_phys.sim import Simulation
from mresim_phys.strategies.params import FrontierParams

MakeScenario = Callable[..., Path]

TEAM: dict[str, Any] = {"speed": 2, "radius": 1.0, "sensor": {"range": 30}, "comm_range": 20}


def team(**changes: Any) -> dict[str, Any]:
    """The conftest team with ``changes`` applied."""
    return {**TEAM, **changes}


def robot(name: str = "A", start: tuple[float, float] = (8, 20), **fields: Any) -> dict[str, Any]:
    return {"name": name, "start": list(start), **fields}


def load_error(path: Path) -> str:
    """The ScenarioError message raised by loading ``path``."""
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    return str(info.value)


def build_error(path: Path) -> str:
    """The ScenarioError message raised by building a simulation from ``path``."""
    with pytest.raises(ScenarioError) as info:
        Simulation(load_scenario(path))
    return str(info.value)


# --- valid scenarios ---------------------------------------------------------------------


def test_valid_scenario_loads(scenario_file: MakeScenario) -> None:
    scenario = load_scenario(scenario_file(steps=5))
    assert isinstance(scenario, Scenario)
    assert scenario.name == "tiny"
    assert scenario.steps == 5
    assert [r.name for r in scenario.robots] == ["A", "B"]


def test_team_defaults_are_inherited_and_robot_overrides_win(
    scenario_file: MakeScenario,
) -> None:
    a, b = load_scenario(scenario_file()).robots
    assert (a.speed, a.radius, a.comm_range, a.sensor.range) == (2, 1.0, 20, 30)
    assert (b.radius, b.comm_range, b.sensor.range) == (1.0, 20, 30)
    assert b.speed == 3


def test_robot_partial_sensor_merges_with_team_sensor(scenario_file: MakeScenario) -> None:
    path = scenario_file(
        team=team(sensor={"range": 30, "fov_deg": 90, "rays": 45}),
        robots=[robot("A"), robot("B", (8, 40), sensor={"range": 200})],
    )
    a, b = load_scenario(path).robots
    assert (a.sensor.range, a.sensor.fov_deg, a.sensor.rays) == (30, 90, 45)
    assert (b.sensor.range, b.sensor.fov_deg, b.sensor.rays) == (200, 90, 45)


def test_relative_map_path_resolves_against_the_yaml_folder(
    scenario_file: MakeScenario, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    scenario_file()
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    kind, value = load_scenario(Path("../scenario.yaml")).map.source
    resolved = Path(value)
    assert kind == "image"
    assert resolved.is_absolute()
    assert resolved.exists()
    assert resolved == (tmp_path / "rooms.png").resolve()


@pytest.mark.parametrize("communication", [{"model": "disk"}, "disk"])
def test_communication_model_by_name(
    scenario_file: MakeScenario, communication: dict[str, str] | str
) -> None:
    scenario = load_scenario(scenario_file(communication=communication))
    assert scenario.communication.model == "disk"
    assert scenario.communication.params == {}


def test_strategy_shorthand_gets_every_default_param(scenario_file: MakeScenario) -> None:
    scenario = load_scenario(scenario_file(team=team(strategy="frontier")))
    defaults = FrontierParams().model_dump()
    assert scenario.team.strategy.name == "frontier"
    assert scenario.team.strategy.params == defaults
    for r in scenario.robots:
        assert r.strategy.name == "frontier"
        assert r.strategy.params["min_frontier_size"] == defaults["min_frontier_size"]


def test_strategy_with_params_keeps_them_and_fills_the_rest(
    scenario_file: MakeScenario,
) -> None:
    strategy = {"name": "frontier", "params": {"replan_interval": 5}}
    path = scenario_file(robots=[robot("A", strategy=strategy), robot("B", (8, 40))])
    a, b = load_scenario(path).robots
    assert a.strategy.params["replan_interval"] == 5
    assert a.strategy.params["min_frontier_size"] == FrontierParams().min_frontier_size
    assert b.strategy.params["replan_interval"] == FrontierParams().replan_interval


def test_load_overrides_replace_top_level_keys(scenario_file: MakeScenario) -> None:
    scenario = load_scenario(scenario_file(), steps=7, seed=11)
    assert (scenario.steps, scenario.seed) == (7, 11)


# --- schema errors: file + field path ----------------------------------------------------


@pytest.mark.parametrize(
    ("changes", "expected"),
    [
        pytest.param({"stpes": 5}, ["stpes", "did you mean 'steps'"], id="top-level-typo"),
        pytest.param(
            {"team": team(sensor={"range": 30, "rnage": 5})},
            ["team.sensor.rnage", "unknown key"],
            id="nested-typo",
        ),
        pytest.param({"team": team(speed="fast")}, ["team.speed", "'fast'"], id="team-type"),
        pytest.param(
            {"robots": [robot("A", speed="fast")]}, ["robots[0].speed", "'fast'"], id="robot-type"
        ),
        pytest.param({"team": team(speed=-1)}, ["team.speed", "greater than 0"], id="negative"),
        pytest.param(
            {"map": {"image": "rooms.png", "grid": "rooms.txt"}},
            ["map", "exactly one map source"],
            id="two-map-sources",
        ),
        pytest.param(
            {"robots": [robot("A"), robot("A", (8, 40))]},
            ["robots", "unique", "'A'"],
            id="duplicate-names",
        ),
        pytest.param(
            {"events": [{"step": 3, "fail": "Z"}]},
            ["no robot is called 'Z'", "'A'", "'B'"],
            id="event-unknown-robot",
        ),
        pytest.param(
            {"team": team(strategy="fronteir")},
            ["team.strategy.name", "'fronteir'", "did you mean 'frontier'"],
            id="unknown-strategy",
        ),
        pytest.param(
            {"team": team(strategy={"name": "frontier", "params": {"replan_intervall": 3}})},
            ["team.strategy.params.replan_intervall", "unknown key"],
            id="unknown-strategy-param",
        ),
        pytest.param(
            {"communication": {"model": "dsik"}},
            ["communication.model", "'dsik'", "'disk'"],
            id="unknown-comm-model",
        ),
        pytest.param(
            {"team": team(strategy="no_such_pkg.strategies:Mine")},
            ["team.strategy", "cannot import", "no_such_pkg"],
            id="unimportable-class",
        ),
    ],
)
def test_scenario_error_names_file_and_field(
    scenario_file: MakeScenario, changes: dict[str, Any], expected: list[str]
) -> None:
    path = scenario_file(**changes)
    message = load_error(path)
    assert str(path) in message
    for fragment in expected:
        assert fragment.lower() in message.lower(), f"{fragment!r} not in {message!r}"


def test_missing_map_key_is_reported(scenario_file: MakeScenario) -> None:
    path = scenario_file()
    data = yaml.safe_load(path.read_text())
    del data["map"]
    path.write_text(yaml.safe_dump(data))
    message = load_error(path)
    assert str(path) in message
    assert "map" in message
    assert "required" in message.lower()


def test_invalid_yaml_names_the_line(tmp_path: Path) -> None:
    path = tmp_path / "broken.yaml"
    path.write_text("name: tiny\nsteps: 5\n  seed: [1\n")
    message = load_error(path)
    assert str(path) in message
    assert "line 3" in message


def test_missing_scenario_file_is_a_scenario_error(tmp_path: Path) -> None:
    path = tmp_path / "nowhere.yaml"
    message = load_error(path)
    assert str(path) in message
    assert "does not exist" in message


def test_unknown_event_robot_error_names_the_event_field(scenario_file: MakeScenario) -> None:
    message = load_error(scenario_file(events=[{"step": 3, "fail": "Z"}]))
    assert "events[0]" in message
    assert "base_station" not in message


@pytest.mark.parametrize(
    ("changes", "good", "bad"),
    [
        pytest.param(
            {"team": team(sensor={"range": 30, "sped": 1})}, None, "'speed'", id="sensor-sped"
        ),
        pytest.param(
            {"team": team(strategy={"name": "frontier", "params": {"replan_intervall": 3}})},
            "did you mean 'replan_interval'",
            None,
            id="param-replan_intervall",
        ),
    ],
)
def test_did_you_mean_hint_is_valid_where_the_typo_is(
    scenario_file: MakeScenario, changes: dict[str, Any], good: str | None, bad: str | None
) -> None:
    message = load_error(scenario_file(**changes))
    if good is not None:
        assert good in message
    if bad is not None:
        assert bad not in message


# --- errors found when building the simulation -------------------------------------------


@pytest.mark.parametrize(
    ("start", "fragments"),
    [
        pytest.param((1, 1), ["wall", "[1.0, 1.0]"], id="in-wall"),
        pytest.param((500, 20), ["outside", "[500.0, 20.0]"], id="outside-map"),
    ],
)
def test_bad_robot_start_names_robot_and_position(
    scenario_file: MakeScenario, start: tuple[float, float], fragments: list[str]
) -> None:
    path = scenario_file(robots=[robot("A"), robot("B", start)])
    message = build_error(path)
    assert "'B'" in message
    for fragment in fragments:
        assert fragment in message


def test_missing_map_file_is_a_map_error(scenario_file: MakeScenario, tmp_path: Path) -> None:
    path = scenario_file(map={"image": "nope.png"})
    with pytest.raises(MapError) as info:
        Simulation(load_scenario(path))
    assert str((tmp_path / "nope.png").resolve()) in str(info.value)


# --- user-defined strategy classes -------------------------------------------------------

PLUGIN_SOURCE = '''
from __future__ import annotations

from typing import ClassVar

from mresim_phys.strategies import Decision, RobotView, StrategyParams


class StayParams(StrategyParams):
    patience: int = 1


class Stay:
    """Never moves; remembers who asked."""

    Params = StayParams
    calls: ClassVar[list[str]] = []

    def __init__(self, params: StayParams) -> None:
        self.params = params

    def decide(self, view: RobotView) -> Decision:
        Stay.calls.append(view.name)
        return Decision()


class NoParams:
    def __init__(self, params: object) -> None:
        self.params = params

    def decide(self, view: RobotView) -> Decision:
        return Decision()
'''


@pytest.fixture
def plugin_module(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[str]:
    """A strategy module written into tmp_path and importable; its name."""
    name = "mresim_test_user_strategy"
    (tmp_path / f"{name}.py").write_text(PLUGIN_SOURCE)
    monkeypatch.syspath_prepend(str(tmp_path))
    yield name
    sys.modules.pop(name, None)


def test_user_strategy_class_by_reference_runs(
    scenario_file: MakeScenario, plugin_module: str
) -> None:
    strategy = {"name": f"{plugin_module}:Stay", "params": {"patience": 4}}
    scenario = load_scenario(scenario_file(steps=3, team=team(strategy=strategy)))
    assert scenario.robots[0].strategy.params["patience"] == 4
    assert "replan_interval" in scenario.robots[0].strategy.params
    sim = Simulation(scenario)
    record = sim.run()
    assert record.step == 3
    assert record.distance == 0.0
    calls = sys.modules[plugin_module].Stay.calls
    assert {"A", "B"} <= set(calls)


def test_user_strategy_params_are_validated(
    scenario_file: MakeScenario, plugin_module: str
) -> None:
    strategy = {"name": f"{plugin_module}:Stay", "params": {"patiense": 4}}
    message = load_error(scenario_file(team=team(strategy=strategy)))
    assert "team.strategy.params.patiense" in message


def test_user_strategy_missing_class_is_reported(
    scenario_file: MakeScenario, plugin_module: str
) -> None:
    message = load_error(scenario_file(team=team(strategy=f"{plugin_module}:Missing")))
    assert "'Missing'" in message
    assert plugin_module in message


def test_user_strategy_class_without_params_is_a_scenario_error(
    scenario_file: MakeScenario, plugin_module: str
) -> None:
    message = load_error(scenario_file(team=team(strategy=f"{plugin_module}:NoParams")))
    assert "Params" in message


def test_a_third_party_params_model_gets_the_same_number_checks(
    scenario_file: MakeScenario, plugin_module: str
) -> None:
    for patience, fragment in [(True, "not true or false"), (10**10, "from -1000000000 to")]:
        strategy = {"name": f"{plugin_module}:Stay", "params": {"patience": patience}}
        message = load_error(scenario_file(team=team(strategy=strategy)))
        assert "team.strategy.params.patience" in message and fragment in message


# --- numbers: finite, bounded, never booleans ----------------------------------------------


@pytest.mark.parametrize(
    ("changes", "expected"),
    [
        pytest.param(
            {"team": team(speed=float("inf"))}, "team.speed: Input should be a finite", id="inf"
        ),
        pytest.param({"team": team(speed=True)}, "team.speed: expected a number", id="bool"),
        pytest.param({"team": team(speed=1001)}, "team.speed", id="speed-bound"),
        pytest.param(
            {"robots": [robot("A", heading_deg=2e6)]},
            "robots[0].heading_deg: expected a number from -1e+06 to 1e+06",
            id="generic-float-bound",
        ),
        pytest.param({"steps": 2 * 10**9}, "steps: expected a number of at most", id="int-bound"),
        pytest.param({"render": {"snapshots": [1, True]}}, "render.snapshots", id="bool-in-list"),
        pytest.param(
            {"base_station": {"position": [8, 30], "comm_power_dbm": -301}},
            "base_station.comm_power_dbm: expected a number from -300 to 300",
            id="dbm",
        ),
        pytest.param(
            {"communication": {"model": "line_of_sight", "params": {"clearance": float("nan")}}},
            "communication.params.clearance",
            id="plugin-nan",
        ),
        pytest.param(
            {"events": [{"step": 3, "cells": [40, 25, 42, True]}]}, "events[0].cells", id="event"
        ),
    ],
)
def test_numbers_must_be_finite_bounded_and_not_booleans(
    scenario_file: MakeScenario, changes: dict[str, Any], expected: str
) -> None:
    message = load_error(scenario_file(**changes))
    assert expected in message, message


def test_booleans_stay_valid_where_a_field_takes_them(scenario_file: MakeScenario) -> None:
    render = {"video": False, "final_png": False, "log": True}
    scenario = load_scenario(scenario_file(render=render, map={"image": "rooms.png", "negate": 0}))
    assert scenario.render.video is False and scenario.map.negate is False


def test_bounds_text_reads_own_and_generic_bounds() -> None:
    from mresim_phys.scenario.schema import RobotParams, RobotSpec
    from mresim_phys.strict import bounds_text

    fields = {**RobotParams.model_fields, **RobotSpec.model_fields}
    assert bounds_text("speed", fields["speed"]) == "0 < x <= 1000"
    assert bounds_text("heading_deg", fields["heading_deg"]) == "-1e+06 <= x <= 1e+06"
    assert bounds_text("comm_power_dbm", fields["comm_power_dbm"]) == "-300 <= x <= 300"
    assert bounds_text("name", fields["name"]) == ""


@pytest.mark.parametrize("name", [".", "..", "...", "-", ".-.", "a/b", "a b", "x" * 65, ""])
def test_names_that_could_leave_the_run_folder_are_rejected(
    scenario_file: MakeScenario, name: str
) -> None:
    assert "name" in load_error(scenario_file(name=name))
    assert "robots[1].name" in load_error(scenario_file(robots=[robot("A"), robot(name)]))


@pytest.mark.parametrize("name", ["a", "_", "..a", "run.2", "-x-", "x" * 64])
def test_names_with_a_letter_digit_or_underscore_are_fine(
    scenario_file: MakeScenario, name: str
) -> None:
    assert load_scenario(scenario_file(name=name)).name == name


def test_snapshots_past_the_step_cap_are_an_error_after_overrides(
    scenario_file: MakeScenario,
) -> None:
    path = scenario_file(steps=60, render={"snapshots": [0, 30, 60]})
    assert load_scenario(path).render.snapshots == [0, 30, 60]
    with pytest.raises(ScenarioError, match=r"render\.snapshots: steps \[30, 60\] past"):
        load_scenario(path, steps=20)
    assert "render.snapshots[0]" in load_error(scenario_file(render={"snapshots": [-1]}))


# --- YAML: duplicate keys, depth, odd values -----------------------------------------------


def write_text(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "raw.yaml"
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        pytest.param("name: a\nseed: 1\nseed: 2\n", "line 3, column 1: key 'seed'", id="top"),
        pytest.param(
            "name: a\nteam:\n  speed: 1\n  radius: 1\n  speed: 2\n",
            "key 'speed' appears twice (first at line 3)",
            id="nested",
        ),
        pytest.param("robots: [{name: A, name: B}]\n", "key 'name' appears twice", id="flow"),
        pytest.param("a: " + "[" * 5000 + "]" * 5000 + "\n", "nested too deeply", id="deep"),
        pytest.param("seed: 2001-13-01\n", "line 1, column 7: cannot read the value", id="date"),
        pytest.param("seed: !!python/object:os.system ls\n", "line 1", id="python-tag"),
    ],
)
def test_yaml_problems_are_scenario_errors_with_a_place(
    tmp_path: Path, text: str, expected: str
) -> None:
    message = load_error(write_text(tmp_path, text))
    assert expected in message and str(tmp_path) in message, message


def test_merge_keys_are_not_duplicates() -> None:
    from mresim_phys.scenario.yamlfile import parse_yaml

    text = "a: &x {p: 1, q: 2}\nb:\n  <<: *x\n  q: 3\n"
    assert parse_yaml(text) == {"a": {"p": 1, "q": 2}, "b": {"p": 1, "q": 3}}


# --- plugin references ---------------------------------------------------------------------


@pytest.mark.parametrize(
    ("reference", "expected"),
    [
        (":", "a part is empty"),
        ("a:", "a part is empty"),
        (":Frontier", "a part is empty"),
        (" : ", "a part is empty"),
        ("..relative:X", "cannot import '..relative'"),
        ("no_such_pkg.sub:X", "cannot import 'no_such_pkg.sub'"),
        ("os:path", "has a module but no class 'path'"),
        ("mresim_phys.cli:main", "has a function but no class 'main'"),
        ("mresim_phys.cli:Nope", "has no class 'Nope'"),
        ("a\x00b:C", "cannot import"),
    ],
)
def test_every_bad_class_reference_is_an_unknown_plugin_error(
    reference: str, expected: str
) -> None:
    from mresim_phys.errors import UnknownPluginError
    from mresim_phys.strategies import STRATEGIES

    with pytest.raises(UnknownPluginError, match=re.escape(expected)):
        STRATEGIES.get(reference)


def test_a_broken_entry_point_is_named_when_asked_for(monkeypatch: pytest.MonkeyPatch) -> None:
    import mresim_phys.registry as registry_module
    from mresim_phys.errors import UnknownPluginError

    class Broken:
        name, value = "broken", "gone_pkg:Thing"

        def load(self) -> type:
            raise ImportError("No module named 'gone_pkg'")

    monkeypatch.setattr(registry_module, "entry_points", lambda group: [Broken()])
    things: registry_module.Registry[object] = registry_module.Registry("thing", "test.group")
    assert things.names() == []
    with pytest.raises(UnknownPluginError, match=r"'broken' \(entry point 'gone_pkg:Thing'\)"):
        things.get("broken")


# --- the base station and robot bodies against the world ---------------------------------


@pytest.mark.parametrize(
    ("position", "fragment"), [((1, 1), "inside a wall"), ((40, 10), "inside a wall")]
)
def test_a_base_station_inside_a_wall_is_rejected(
    scenario_file: MakeScenario, position: tuple[int, int], fragment: str
) -> None:
    message = build_error(scenario_file(base_station={"position": list(position)}))
    assert "base_station.position" in message and fragment in message


def test_overlapping_starts_are_rejected_only_when_robots_block(
    scenario_file: MakeScenario,
) -> None:
    crowd = [robot(f"R{i}", (8, 20)) for i in range(40)]
    path = scenario_file(robots=crowd, simulation={"robots_block": True})
    message = build_error(path)
    assert "'R0' and 'R1'" in message and "more pairs" in message and "robots_block" in message
    Simulation(load_scenario(scenario_file(robots=crowd)))  # without blocking: allowed
    apart = [robot("A", (8, 20)), robot("B", (8, 22))]  # radius 1: touching, not overlapping
    Simulation(load_scenario(scenario_file(robots=apart, simulation={"robots_block": True})))


def test_an_override_does_not_hide_a_malformed_section(scenario_file: MakeScenario) -> None:
    with pytest.raises(ScenarioError, match=r"render: Input should be a valid dictionary"):
        load_scenario(scenario_file(render=5), render={"plots": False})  # as `run --no-plots`
