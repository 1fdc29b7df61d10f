"""Documentation stays true: the strategy example runs, the generated reference is current."""

from __future__ import annotations

import re
import sys
from collections.abc import Callable
from pathlib import Path

import pytest
from tool_modules import load_tool

from mresim_phys import Simulation

ROOT = Path(__file__).parent.parent


def python_blocks(path: Path) -> list[str]:
    return re.findall(r"```python\n(.*?)```", path.read_text(encoding="utf-8"), re.S)


def importable_example(
    index: int, module: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Python block ``index`` of the strategy guide saved as ``module`` on the path."""
    (tmp_path / f"{module}.py").write_text(
        python_blocks(ROOT / "docs/writing-a-strategy.md")[index]
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, module, raising=False)


def test_strategy_example_runs(
    tmp_path: Path, scenario_file: Callable[..., Path], monkeypatch: pytest.MonkeyPatch
) -> None:
    importable_example(0, "my_strategies", tmp_path, monkeypatch)
    strategy = {"name": "my_strategies:NearestFrontier", "params": {"min_size": 5}}
    team = {"speed": 2, "radius": 1.0, "sensor": {"range": 30}, "comm_range": 20}
    sim = Simulation.from_yaml(scenario_file(team={**team, "strategy": strategy}, steps=40))
    last = sim.run()
    assert last.explored > 0.5


def test_scenario_reference_is_current() -> None:
    module = load_tool("make_scenario_reference")
    committed = (ROOT / "docs/scenario-reference.md").read_text(encoding="utf-8")
    assert committed == module.render(), "run: python tools/make_scenario_reference.py"


def test_readme_commands_are_the_ones_ci_runs() -> None:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert 'pip install -e ".[test]" && pytest' in readme
    assert "pip install -e . && mresim warmup && mresim run scenarios/01_quickstart.yaml" in readme
    assert (ROOT / "scenarios/01_quickstart.yaml").exists()
    ci = (ROOT / ".ci/run").read_text()
    assert 'pip install -e ".[test,dev]"' in ci  # the README's install, plus the checkers
    for command in ("ruff check .", "ruff format --check .", "mypy", "pytest"):
        assert f"\n{command}\n" in ci, f".ci/run does not run {command!r}"
    assert re.search(r"--cov-fail-under=\d+", ci), ".ci/run has no coverage floor"


def test_coordination_example_runs(
    tmp_path: Path, scenario_file: Callable[..., Path], monkeypatch: pytest.MonkeyPatch
) -> None:
    importable_example(2, "meet_strategies", tmp_path, monkeypatch)
    team = {"speed": 2, "radius": 1.0, "sensor": {"range": 30}, "comm_range": 20}
    strategy = {"name": "meet_strategies:MeetAtBase"}
    sim = Simulation.from_yaml(scenario_file(team={**team, "strategy": strategy}, steps=20))
    sim.run()
    heard = sim.robot("A").teammates["B"]
    assert heard.payload is not None and heard.payload.point == sim.base.position


def test_the_strategy_built_from_parts_spreads_the_team(
    tmp_path: Path, scenario_file: Callable[..., Path], monkeypatch: pytest.MonkeyPatch
) -> None:
    """The guide's strategy from parts runs with its own allocation in place of the
    auction, and explores."""
    importable_example(1, "my_parts", tmp_path, monkeypatch)
    import my_parts

    from mresim_phys.strategies.parts import GreedyAuction

    team = {"speed": 2, "radius": 1.0, "sensor": {"range": 30}, "comm_range": 20}
    sim = Simulation.from_yaml(
        scenario_file(team={**team, "strategy": "my_parts:Spread"}, steps=60)
    )
    strategy = sim.robot("A").strategy
    assert isinstance(strategy.parts.allocation, my_parts.AwayFromTeammates)
    assert not isinstance(strategy.parts.allocation, GreedyAuction)
    last = sim.run()
    assert last.explored > 0.5


def documented_names(path: Path) -> set[str]:
    return set(re.findall(r"`(\w+)`", path.read_text(encoding="utf-8")))


def test_the_strategy_guide_documents_every_view_and_decision_field() -> None:
    from dataclasses import fields

    from mresim_phys.strategies import Decision, RobotView

    names = documented_names(ROOT / "docs/writing-a-strategy.md")
    missing = [f.name for cls in (RobotView, Decision) for f in fields(cls) if f.name not in names]
    assert missing == [], f"docs/writing-a-strategy.md does not mention {missing}"


def test_the_plugin_contracts_in_the_guide_match_the_protocols() -> None:
    import inspect

    from mresim_phys.comms import CommModel
    from mresim_phys.planning import Planner
    from mresim_phys.strategies import Strategy
    from mresim_phys.world.event_api import Event

    text = (ROOT / "docs/writing-a-strategy.md").read_text(encoding="utf-8")
    for protocol, methods in (
        (Strategy, ["decide"]),
        (CommModel, ["links", "reach"]),
        (Planner, ["plan", "info"]),
        (Event, ["apply"]),
    ):
        for method in methods:
            params = list(inspect.signature(getattr(protocol, method)).parameters)[1:]
            call = f"{method}({', '.join(params)})"
            with_self = f"{method}({', '.join(['self', *params])})"
            assert call in text or with_self in text, f"the guide lacks {call}"


def test_the_readme_scenario_example_validates_and_builds() -> None:
    import yaml

    from mresim_phys.scenario.load import validate_scenario

    block = re.findall(r"```yaml\n(.*?)```", (ROOT / "README.md").read_text(encoding="utf-8"), re.S)
    data = yaml.safe_load(block[0])
    data["map"]["image"] = str(ROOT / "maps" / "office.png")
    sim = Simulation(validate_scenario(data, "README.md"))
    assert [r.name for r in sim.robots] == ["A", "B"]
