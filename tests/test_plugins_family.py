"""Plugin references of the wrong family are refused when resolved, naming field and family.

A ``package.module:Class`` reference (or an entry point) naming a class of another family,
a strategy given as a planner, a comm model given as a strategy, used to be accepted and
the run died with a traceback; now ``mresim validate``, ``mresim run`` and ``mresim sweep``
refuse it (exit 2) before anything runs.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import yaml

from mresim_phys.cli import main
from mresim_phys.errors import UnknownPluginError
from mresim_phys.planning import PLANNERS
from mresim_phys.strategies import STRATEGIES

FRONTIER = "mresim_phys.strategies.frontier:FrontierExploration"
DISK = "mresim_phys.comms.disk:DiskComm"
ASTAR = "mresim_phys.planning.astar:AStar"
FAIL = "mresim_phys.world.events:Failure"
WORLD = "mresim_phys.world.space:World"  # a class of no family


def team(**plugins: Any) -> dict[str, Any]:
    return {"speed": 2, "radius": 1.0, "sensor": {"range": 30}, "comm_range": 20, **plugins}


WRONG: list[Any] = [
    pytest.param({"team": team(planner=FRONTIER)}, "team.planner", "a strategy, not a planner"),
    pytest.param(
        {"team": team(strategy=DISK)}, "team.strategy", "a communication model, not a strategy"
    ),
    pytest.param({"team": team(strategy=ASTAR)}, "team.strategy", "a planner, not a strategy"),
    pytest.param(
        {"team": team(strategy={"name": FAIL, "params": {"step": 1, "fail": "A"}})},
        "team.strategy",
        "an event, not a strategy",
        id="event-as-strategy",
    ),
    pytest.param(
        {"communication": {"model": FRONTIER}},
        "communication.model",
        "a strategy, not a communication model",
    ),
    pytest.param(
        {"communication": {"model": "disk", "control": {"model": ASTAR}}},
        "communication.control.model",
        "a planner, not a communication model",
    ),
    pytest.param({"team": team(planner=WORLD)}, "team.planner", "it is not a planner"),
]


@pytest.mark.parametrize(("changes", "field", "family"), WRONG)
def test_a_class_of_another_family_is_refused_naming_field_and_family(
    scenario_file: Callable[..., Path],
    capsys: pytest.CaptureFixture[str],
    changes: dict[str, Any],
    field: str,
    family: str,
) -> None:
    path = scenario_file(**changes)
    capsys.readouterr()
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"mresim: error: {path}: {field}") and family in err, err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_the_message_says_what_the_family_needs() -> None:
    with pytest.raises(UnknownPluginError) as caught:
        PLANNERS.get(FRONTIER)
    text = str(caught.value)
    assert "subclassing PlannerParams" in text and "plan(), info()" in text
    assert "FrontierParams, not a subclass of PlannerParams" in text


def test_a_robots_own_plugin_is_checked_too(
    scenario_file: Callable[..., Path], capsys: pytest.CaptureFixture[str]
) -> None:
    robots = [{"name": "A", "start": [8, 20], "planner": FRONTIER}, {"name": "B", "start": [8, 40]}]
    path = scenario_file(robots=robots)
    capsys.readouterr()
    assert main(["run", str(path), "--steps", "2", "--quiet", "--no-plots"]) == 2
    err = capsys.readouterr().err
    assert "robots[0].planner" in err and "a strategy, not a planner" in err, err


def test_a_sweep_axis_naming_another_family_is_refused_before_running(
    scenario_file: Callable[..., Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    study = tmp_path / "study.yaml"
    data = {
        "name": "family",
        "scenarios": [str(scenario_file())],
        "axes": {"team.strategy": ["frontier", DISK]},
        "seeds": 1,
        "steps": 3,
    }
    study.write_text(yaml.safe_dump(data), encoding="utf-8")
    capsys.readouterr()
    code = main(["sweep", str(study), "--out", str(tmp_path / "out"), "--workers", "1"])
    err = capsys.readouterr().err
    assert code == 2 and "arm 1" in err and "team.strategy" in err, err
    assert "a communication model, not a strategy" in err and not (tmp_path / "out").exists()


def test_a_class_of_the_right_family_by_reference_still_works() -> None:
    assert STRATEGIES.get("mresim_phys.strategies.random_walk:RandomWalk").name == "random_walk"
    assert PLANNERS.get(ASTAR).name == "astar"


def test_an_entry_point_of_another_family_is_named_when_asked_for(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    import mresim_phys.registry as registry_module
    from mresim_phys.planning.astar import AStar
    from mresim_phys.plugin import Family
    from mresim_phys.strategies.base import Strategy
    from mresim_phys.strategies.params import StrategyParams

    class Point:
        name, value = "astar_as_strategy", "mresim_phys.planning.astar:AStar"

        def load(self) -> type:
            return AStar

    monkeypatch.setattr(registry_module, "entry_points", lambda group: [Point()])
    family = Family(Strategy, StrategyParams)
    mine: registry_module.Registry[Any] = registry_module.Registry("strategy", "test.g", family)
    assert mine.names() == []
    with pytest.raises(UnknownPluginError, match="it is a planner, not a strategy"):
        mine.get("astar_as_strategy")


def test_registering_a_class_of_another_family_is_an_error() -> None:
    from mresim_phys.planning.astar import AStar

    class Impostor(AStar):
        name = "impostor"

    with pytest.raises(ValueError, match="it is a planner, not a strategy"):
        STRATEGIES.register(Impostor)
    assert "impostor" not in STRATEGIES.names()
