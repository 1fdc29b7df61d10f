"""The contract for strategies that coordinate: payloads that travel only along links and are
counted in bytes, role changes, what a RobotView tells, and decisions from outside."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pytest

from mresim_phys import Simulation
from mresim_phys.knowledge.teammates import RECORD_BYTES, Payload, TeammateInfo, presumed_lost
from mresim_phys.strategies import STRATEGIES, Decision, RobotView
from mresim_phys.strategies.frontier import FrontierExploration

ScenarioFile = Callable[..., Path]


@dataclass(frozen=True)
class Meeting(Payload):
    """Where and when a robot proposes to meet."""

    point: tuple[float, float]
    step: int


class Proposer(FrontierExploration):
    """Frontier exploration that proposes a meeting and turns relay at step 6."""

    name = "test_proposer"
    seen: list[RobotView] = []  # noqa: RUF012 (the test reads what the strategy saw)

    def decide(self, view: RobotView) -> Decision:
        Proposer.seen.append(view)
        decision = super().decide(view)
        role = "relay" if view.step >= 6 else None
        return replace(decision, payload=Meeting(view.position, view.step + 50), role=role)


@pytest.fixture
def proposer() -> object:
    STRATEGIES.register(Proposer)
    Proposer.seen = []
    yield Proposer
    STRATEGIES._classes.pop(Proposer.name)


def test_payload_size_is_the_sum_of_its_fields() -> None:
    meeting = Meeting((1.0, 2.0), 7)
    assert meeting.nbytes() == 16 + 8
    record = TeammateInfo("A", (0.0, 0.0), None, "active", "explorer", 3, payload=meeting)
    assert record.nbytes() == RECORD_BYTES + 24


def test_payloads_travel_along_links_only_and_are_counted(
    scenario_file: ScenarioFile, proposer: object
) -> None:
    team = {"speed": 2, "radius": 1.0, "sensor": {"range": 30}, "comm_range": 20}
    path = scenario_file(
        team=team,
        robots=[
            {"name": "A", "start": [8, 20], "strategy": "test_proposer"},
            {"name": "B", "start": [8, 40]},
        ],
        base_station={"position": [75, 50], "comm_range": 0},
        steps=8,
    )
    sim = Simulation.from_yaml(path)
    sim.step()
    heard = sim.robot("B").teammates["A"]
    assert isinstance(heard.payload, Meeting) and heard.payload.step == heard.step + 50
    plain = Simulation.from_yaml(path, robots={"A": {"strategy": "frontier"}})
    plain.step()
    assert sim.record.comm_bytes > plain.record.comm_bytes  # the payload cost bytes
    assert "A" not in sim.base.teammates  # the base, out of range, never got it


def test_a_decision_can_change_the_role(scenario_file: ScenarioFile, proposer: object) -> None:
    path = scenario_file(
        team={"strategy": "test_proposer", "speed": 2, "radius": 1.0, "comm_range": 20}
    )
    sim = Simulation.from_yaml(path)
    for _ in range(20):
        sim.step()
    assert {r.role for r in sim.robots} == {"relay"}
    assert sim.robot("B").teammates["A"].role == "relay"


def test_a_view_tells_links_base_contact_comm_range_and_lost_teammates(
    scenario_file: ScenarioFile, proposer: object
) -> None:
    path = scenario_file(
        team={"strategy": "test_proposer", "speed": 2, "radius": 1.0, "comm_range": 20}
    )
    sim = Simulation.from_yaml(path)
    for _ in range(16):
        sim.step()
    view = sim.view_of(sim.robot("A"))
    assert view.comm_range == 20.0
    assert set(view.links) == {a.name for a, on in zip(sim.agents, sim.links[1], strict=True) if on}
    assert view.base_contact == sim.robot("A").last_base_contact
    assert view.lost == frozenset()
    assert any(v.links for v in Proposer.seen)
    old = TeammateInfo("B", (0.0, 0.0), None, "active", "explorer", step=2)
    assert presumed_lost({"B": old, "base": old}, step=300, silence=200) == {"B"}


def test_an_outside_controller_drives_a_robot_for_a_step(scenario_file: ScenarioFile) -> None:
    sim = Simulation.from_yaml(scenario_file())
    robot = sim.robot("A")
    x, y = robot.position
    target = (x + 1.5, y)
    sim.step(actions={"A": Decision(path=np.array([target]), goal=target)})
    assert robot.position == pytest.approx(target)
    assert robot.goal == target
    with pytest.raises(ValueError, match="'Z'"):
        sim.step(actions={"Z": Decision()})


def test_controlled_and_uncontrolled_runs_agree_when_the_controller_copies_the_strategy(
    scenario_file: ScenarioFile,
) -> None:
    """Supplying exactly what the strategy would decide changes nothing."""
    path = scenario_file(steps=30)
    auto, driven = Simulation.from_yaml(path), Simulation.from_yaml(path)
    for _ in range(25):
        auto.step()
        robot = driven.robot("A")
        assert robot.strategy is not None
        actions = {}
        if (
            robot.status == "error"
            or robot.reached_goal
            or driven.t + 1 - robot.last_plan_step >= 15
        ):
            view = replace(driven.view_of(robot), step=driven.t + 1)
            actions = {"A": robot.strategy.decide(view)}
        driven.step(actions=actions)
    assert auto.record == driven.record
