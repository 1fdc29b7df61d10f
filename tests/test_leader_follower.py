"""``leader_follower`` and the team's hierarchy: the chain never breaks, a robot out of its
parent's reach steps back, and bad hierarchies are errors naming the robots."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mresim_phys.errors import ScenarioError
from mresim_phys.knowledge.teammates import TeammateInfo
from mresim_phys.sim import Simulation
from mresim_phys.strategies import RobotView
from mresim_phys.strategies.leader_follower import LeaderFollower
from mresim_phys.strategies.params import LeaderFollowerParams
from mresim_phys.types import FREE, OCCUPIED

MakeScenario = Callable[..., Path]
CHAIN = [
    {"name": "R1", "start": [8, 20], "parent": "base", "role": "relay"},
    {"name": "R2", "start": [12, 20], "parent": "R1", "role": "relay"},
    {"name": "E", "start": [16, 20], "parent": "R2"},
]
TEAM = {"speed": 2, "radius": 1.0, "sensor": {"range": 20}, "comm_range": 12}


def chain_scenario(scenario_file: MakeScenario, **changes: Any) -> Path:
    data: dict[str, Any] = {
        "steps": 300,
        "stop": {"explored": 0.99},
        "base_station": {"position": [8, 30], "comm_range": 10},
        "team": {**TEAM, "strategy": "leader_follower"},
        "robots": CHAIN,
    }
    return scenario_file(**(data | changes))


def test_the_chain_never_breaks_and_the_leader_explores(scenario_file: MakeScenario) -> None:
    sim = Simulation.from_yaml(chain_scenario(scenario_file))
    names = [a.name for a in sim.agents]
    assert [(r.name, r.parent, r.children, r.hops) for r in sim.robots] == [
        ("R1", "base", ("R2",), 1),
        ("R2", "R1", ("E",), 2),
        ("E", "R2", (), 3),
    ]
    base_x, base_y = sim.base.position
    while not sim.finished():
        record = sim.step()
        for robot in sim.robots:
            parent = names.index(robot.parent or "")
            assert sim.links[names.index(robot.name), parent], (record.step, robot.name)
        x, y = sim.robot("E").position
        assert np.hypot(x - base_x, y - base_y) <= 12 * 3  # within the chain's reach
    assert record.explored > 0.3
    assert record.known_at_base == pytest.approx(record.explored, abs=0.02)  # base hears all


def open_view(links: tuple[str, ...], position: tuple[float, float]) -> RobotView:
    belief = np.full((40, 60), FREE, dtype=np.uint8)
    belief[0, :] = belief[-1, :] = belief[:, 0] = belief[:, -1] = OCCUPIED
    parent = TeammateInfo("R1", (10.5, 20.5), None, "active", "relay", step=4)
    return RobotView(
        step=5, name="E", position=position, heading=0.0, belief=belief, radius=0.5,
        clearance=1.0, speed=2.0, sensor_range=10.0, role="explorer",
        base_position=(5.5, 20.5), teammates={"R1": parent}, rng=np.random.default_rng(0),
        links=links, comm_range=12.0, parent="R1", hops=2, vary_with_seed=False,
    )  # fmt: skip


def test_out_of_its_parents_reach_a_robot_steps_back() -> None:
    strategy = LeaderFollower(LeaderFollowerParams())
    strategy.decide(open_view(("R1",), (15.5, 20.5)))  # linked here
    back = strategy.decide(open_view((), (30.5, 20.5)))  # the link broke
    assert back.info.get("stepping_back")
    assert back.goal is not None and np.hypot(back.goal[0] - 15.5, back.goal[1] - 20.5) < 1.5


def test_a_path_is_cut_where_it_would_leave_the_parents_range() -> None:
    decision = LeaderFollower(LeaderFollowerParams()).decide(open_view(("R1",), (15.5, 20.5)))
    parent = np.array([10.5, 20.5])
    assert len(decision.path) and (np.hypot(*(decision.path - parent).T) <= 12 - 2).all()


@pytest.mark.parametrize(
    ("robots", "message"),
    [
        ([{**CHAIN[0], "parent": "R9"}, *CHAIN[1:]], "neither 'base' nor a robot"),
        ([{**CHAIN[0], "parent": "E"}, *CHAIN[1:]], "cycle"),
        ([*CHAIN[:2], {**CHAIN[2], "parent": "R1"}], "R2 is a relay but no robot names it"),
    ],
)
def test_bad_hierarchies_are_errors_naming_the_robots(
    scenario_file: MakeScenario, robots: list[dict[str, Any]], message: str
) -> None:
    with pytest.raises(ScenarioError, match=message):
        Simulation.from_yaml(chain_scenario(scenario_file, robots=robots))
