"""``role_switch``: the dynamic hierarchy rule, swaps agreed through payloads (one per step
among robots in contact), the second rule for two relays, and a relay whose explorer fails
becoming an explorer."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mresim_phys.build import load_scenario
from mresim_phys.errors import ScenarioError
from mresim_phys.knowledge.teammates import PAYLOAD
from mresim_phys.output.bench import PRESETS, team_scenario
from mresim_phys.scenario.load import validate_scenario
from mresim_phys.sim import Simulation
from mresim_phys.strategies import RobotView
from mresim_phys.strategies.params import RoleSwitchParams
from mresim_phys.strategies.role_switch import RoleSwitch, SwitchPayload
from mresim_phys.types import FREE, OCCUPIED

MakeScenario = Callable[..., Path]
SCENARIO = Path(__file__).parent.parent / "scenarios" / "25_library_role_switch.yaml"


def corridor_view(position: tuple[float, float]) -> RobotView:
    belief = np.full((20, 80), OCCUPIED, dtype=np.uint8)
    belief[8:12, 2:78] = FREE  # one west-east corridor, the base at its west end
    return RobotView(
        step=10, name="X", position=position, heading=0.0, belief=belief, radius=0.5,
        clearance=0.5, speed=2.0, sensor_range=10.0, role="explorer",
        base_position=(4.5, 10.5), teammates={}, rng=np.random.default_rng(0),
    )  # fmt: skip


def test_the_dynamic_hierarchy_rule() -> None:
    strategy = RoleSwitch(RoleSwitchParams())
    # X deep in the west must cross the corridor to its frontier; Y, near that frontier,
    # heads home: swapping shortens the longer trip (max(a1, a2) > max(b1, b2))
    far = corridor_view((10.5, 10.5))
    assert strategy._rule(far, (70.5, 10.5), (60.5, 10.5), (4.5, 10.5))
    # each already nearer its own goal: no swap
    near = corridor_view((65.5, 10.5))
    assert not strategy._rule(near, (70.5, 10.5), (20.5, 10.5), (4.5, 10.5))


def components(sim: Simulation) -> dict[str, int]:
    """Each robot's group of robots in contact (multi-hop over the last exchange)."""
    group: dict[str, int] = {}
    for i, robot in enumerate(sim.robots):
        if robot.name in group:
            continue
        todo = [robot.name]
        while todo:
            name = todo.pop()
            if name not in group:
                group[name] = i
                todo += [n for n in sim.robot(name).links if n != "base"]
    return group


def offers_seen(sim: Simulation, name: str) -> dict[str, str]:
    """The offers a robot hears over its links: offerer -> the teammate it offers to."""
    seen = {}
    for other in sim.robot(name).links:
        payload = PAYLOAD.state_of(sim.robot(other).features) if other != "base" else None
        if isinstance(payload, SwitchPayload) and payload.offer is not None:
            seen[other] = payload.offer[0]
    return seen


def test_swaps_are_agreed_one_at_a_time_among_robots_that_hear_each_other() -> None:
    sim = Simulation(load_scenario(SCENARIO, steps=200))
    order = list(sim.setup.team_order)  # the tie-break order the offers rank by
    accepted = {r.name: None for r in sim.robots}
    offers = acceptances = 0
    while not sim.finished():
        heard = {r.name: offers_seen(sim, r.name) for r in sim.robots}
        sim.step()
        swaps = []
        for robot in sim.robots:
            strategy = robot.strategy
            sent = PAYLOAD.state_of(robot.features)
            assert isinstance(strategy, RoleSwitch) and isinstance(sent, SwitchPayload)
            offers += sent.offer is not None
            if strategy.accepted != accepted[robot.name]:
                assert strategy.accepted is not None
                offerer = strategy.accepted[0]
                swaps += [robot.name, offerer]
                earlier = [o for o in heard[robot.name] if order.index(o) < order.index(offerer)]
                assert not earlier  # it heard no offer ranking before the one it took
                accepted[robot.name] = strategy.accepted
        acceptances += len(swaps) // 2
        assert len(swaps) == len(set(swaps))  # no robot is in two swaps in one step
    assert offers and acceptances >= 2
    playing = sorted(r.strategy.acting for r in sim.robots)  # type: ignore[attr-defined]
    assert playing == sorted(r.name for r in sim.robots)  # every position played once
    assert any(r.strategy.acting != r.name for r in sim.robots)  # type: ignore[attr-defined]
    assert sum(r.strategy.sent_back for r in sim.robots) >= 1  # type: ignore[attr-defined]


def pair(scenario_file: MakeScenario, **changes: Any) -> Path:
    data: dict[str, Any] = {
        "steps": 400,
        "stop": {"known_at_base": 0.95},
        "base_station": {"position": [6, 30], "comm_range": 4},
        "team": {"speed": 2, "radius": 1.0, "sensor": {"range": 15}, "comm_range": 4,
                 "strategy": "role_switch"},
        "robots": [
            {"name": "R", "start": [10, 30], "role": "relay", "parent": "base"},
            {"name": "E", "start": [12, 34], "parent": "R"},
        ],
    }  # fmt: skip
    return scenario_file(**(data | changes))


def test_a_relay_whose_explorer_fails_becomes_an_explorer(scenario_file: MakeScenario) -> None:
    path = pair(scenario_file, steps=600, events=[{"step": 40, "fail": "E"}])
    sim = Simulation.from_yaml(path)
    roles = []
    while not sim.finished():
        sim.step()
        roles.append(sim.robot("R").role)
    assert roles[0] == "relay" and roles[-1] == "explorer"
    assert sim.record.known_at_base >= 0.95 and sim.t < 600  # no endless wait


def test_role_switch_without_relays_is_an_error(scenario_file: MakeScenario) -> None:
    loners = [{"name": "A", "start": [10, 30]}, {"name": "B", "start": [12, 34]}]
    with pytest.raises(ScenarioError, match="A, B use the strategy role_switch"):
        Simulation.from_yaml(pair(scenario_file, robots=loners))


def test_the_benchmark_pairs_its_team_for_relay_strategies() -> None:
    preset = PRESETS["original"]
    data = team_scenario(4, preset.map_path, 5, preset, 1, "role_based:multi_point")
    scenario = validate_scenario(data)
    assert [(r.role, r.parent) for r in scenario.robots] == [
        ("relay", "base"), ("explorer", "R0"), ("relay", "base"), ("explorer", "R2"),
    ]  # fmt: skip
    assert scenario.robots[1].strategy.params["rendezvous"] == "multi_point"


def test_the_hierarchy_layer_follows_the_swaps() -> None:
    sim = Simulation(load_scenario(SCENARIO, steps=120))
    while not sim.finished():
        sim.step()
    drawn = {a.name: a.parent for a in sim.snapshot().robots}
    players = {r.strategy.acting: r.name for r in sim.robots}  # type: ignore[attr-defined]
    assert set(drawn.values()) <= {*players.values(), "base", None}
    assert any(drawn[r.name] != r.parent for r in sim.robots)  # the drawn hierarchy moved
    matches = [
        drawn[r.name] == players[r.strategy.position[1]]  # type: ignore[attr-defined]
        for r in sim.robots
        if r.strategy.position[1] not in (None, "base")  # type: ignore[attr-defined]
    ]
    assert matches and sum(matches) >= len(matches) - 1  # who plays its parent's position
