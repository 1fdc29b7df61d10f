"""The ``policy`` strategy (``strategies/policy/``): its candidate table ranks what the robot
knows, its observation is its own knowledge (never the truth), an action heads where it
says, trained policies load from a callable or an ONNX file, and a mistake names the field."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from mresim_phys import Simulation
from mresim_phys.errors import ScenarioError
from mresim_phys.knowledge.frontiers import frontier_mask
from mresim_phys.knowledge.teammates import TeammateInfo
from mresim_phys.scenario.load import load_scenario
from mresim_phys.strategies import RobotView
from mresim_phys.strategies.params import PolicyParams
from mresim_phys.strategies.policy.candidates import CONTINUE, slot_count
from mresim_phys.strategies.policy.loaders import OnnxPolicy
from mresim_phys.strategies.policy.strategy import PolicyStrategy
from mresim_phys.types import FREE, OCCUPIED, UNKNOWN

SCENARIOS = Path(__file__).resolve().parent.parent / "scenarios"
QUICKSTART = SCENARIOS / "01_quickstart.yaml"
NEAREST = "mresim_phys.strategies.policy.reference:nearest_frontier"
LEAST = "mresim_phys.strategies.policy.reference:least_cost"


def corridor_view(position: tuple[float, float], teammates: dict[str, TeammateInfo]) -> RobotView:
    """A known corridor (rows 5-14, columns 20-79), unknown at both ends, walls around."""
    belief = np.full((20, 100), OCCUPIED, dtype=np.uint8)
    belief[5:15, :] = UNKNOWN
    belief[5:15, 20:80] = FREE
    return RobotView(
        step=10, name="A", position=position, heading=0.0, belief=belief, radius=1.0,
        clearance=1.0, speed=2.0, sensor_range=30.0, role="explorer",
        base_position=(50.5, 10.5), teammates=teammates, rng=np.random.default_rng(0),
        team_order=("A", "B"),
    )  # fmt: skip


def external(**params: Any) -> PolicyStrategy:
    return PolicyStrategy(PolicyParams(external=True, **params))


def test_the_table_ranks_frontiers_by_path_then_meetings_then_the_base() -> None:
    mate = TeammateInfo("B", (60.5, 9.5), None, "active", "explorer", 8)
    view = corridor_view((30.5, 10.5), {"B": mate})
    strategy = external(frontiers=3, meet=1)
    table = strategy.look(view)[1]
    assert len(table.valid) == slot_count(3, 1) == 6
    assert table.valid.tolist() == [True, True, True, False, True, True]
    assert table.points[1, 0] < 30 < table.points[2, 0]  # the left end is nearer
    assert table.costs[1] < table.costs[2]
    assert np.hypot(*(table.points[4] - (60.5, 9.5))) < 1.0  # B's last report
    assert np.hypot(*(table.points[5] - (50.5, 10.5))) < 1.0  # the base


def test_a_choice_heads_for_its_slot_and_an_ask_without_answer_keeps_it() -> None:
    view = corridor_view((30.5, 10.5), {})
    strategy = external(frontiers=2, meet=0)
    strategy.answer = 2  # the right end
    decision = strategy.decide(view)
    assert decision.goal is not None and decision.goal[0] > 70
    again = strategy.decide(view)  # asked again within the step: no new answer
    assert again.goal == decision.goal
    strategy.answer = 99  # not a slot: continue
    assert strategy.decide(view).goal == decision.goal


def test_a_robot_with_no_target_that_continues_stands() -> None:
    view = corridor_view((30.5, 10.5), {})
    strategy = external()
    strategy.answer = CONTINUE
    decision = strategy.decide(view)
    assert decision.goal == view.position and len(decision.path) == 0


def test_goal_and_velocity_actions() -> None:
    view = corridor_view((30.5, 10.5), {})
    goal = external(action="goal_cell")
    goal.answer = np.array([0.6, 0.5])
    decision = goal.decide(view)
    assert decision.goal is not None and abs(decision.goal[0] - 60.5) <= 1.0
    drive = external(action="velocity")
    drive.answer = np.array([np.pi, 1.0])  # west, full speed
    decision = drive.decide(view)
    assert decision.path.tolist() == [[28.5, 10.5]]
    assert drive.replan_now(10, view.position, ()) and not goal.replan_now(10, view.position, ())


def policy_scenario(tmp_path: Path, **params: Any) -> Path:
    data = yaml.safe_load(QUICKSTART.read_text())
    data["map"]["image"] = str((SCENARIOS / data["map"]["image"]).resolve())
    data["team"]["strategy"] = {"name": "policy", "params": params}
    path = tmp_path / "policy.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_a_scenario_runs_a_policy_and_its_observation_is_its_own_map(tmp_path: Path) -> None:
    sim = Simulation(load_scenario(policy_scenario(tmp_path, policy=NEAREST)))
    robot = sim.robots[0]
    strategy = robot.strategy
    assert isinstance(strategy, PolicyStrategy)
    for _ in range(5):
        sim.step()
    obs = strategy.observation(sim.view_of(robot), asked=True)
    x, y = (int(v) for v in robot.position)
    window = robot.belief[y - 4 : y + 4, x - 4 : x + 4]
    frontier = frontier_mask(robot.belief)[y - 4 : y + 4, x - 4 : x + 4]
    for k, layer in enumerate((window == FREE, window == OCCUPIED, window == UNKNOWN, frontier)):
        assert (obs["local"][k, 12:20, 12:20] == layer).all()  # the crop is 32 wide
    assert obs["coarse"][2].sum() > 0  # its map still has unknown space, the truth has none
    record = sim.run()
    assert record.explored >= 0.9


def test_an_onnx_policy_takes_the_best_valid_slot(tmp_path: Path) -> None:
    import onnx
    from onnx import TensorProto, helper

    slots = slot_count(6, 2)
    two = helper.make_tensor("i", TensorProto.INT64, [], [2])
    graph = helper.make_graph(
        [
            helper.make_node("Constant", [], ["index"], value=two),
            helper.make_node("Gather", ["candidates", "index"], ["cost"], axis=2),
            helper.make_node("Neg", ["cost"], ["scores"]),
        ],
        "nearest",
        [helper.make_tensor_value_info("candidates", TensorProto.FLOAT, [1, slots, 4])],
        [helper.make_tensor_value_info("scores", TensorProto.FLOAT, [1, slots])],
    )  # fmt: skip
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 13)])
    onnx.save(model, tmp_path / "nearest.onnx")
    policy = OnnxPolicy(tmp_path / "nearest.onnx", slots)
    candidates = np.zeros((slots, 4), dtype=np.float32)
    candidates[:, 2] = [4.0, 0.3, 0.1, 0.05, 0, 0, 0, 0, 0, 0.2]
    mask = np.array([1, 1, 1, 0, 0, 0, 0, 0, 0, 1], dtype=np.int8)
    assert policy({"candidates": candidates, "action_mask": mask}) == 2  # 3 is masked
    path = policy_scenario(tmp_path, onnx="nearest.onnx")
    assert load_scenario(path).team.strategy.params["onnx"] == str(tmp_path / "nearest.onnx")
    by_onnx = Simulation(load_scenario(path))
    by_callable = Simulation(load_scenario(policy_scenario(tmp_path, policy=LEAST)))
    for _ in range(60):  # the file and the callable score alike: the same run
        assert by_onnx.step() == by_callable.step()
    assert by_onnx.record.distance > 0


@pytest.mark.parametrize(
    ("params", "message"),
    [
        ({"policy": "mresim_phys.strategies.policy.reference:nope"}, "params.policy: policy"),
        ({"policy": "no_such_module:act"}, "params.policy: policy"),
        ({"onnx": "missing.onnx"}, "params.onnx: no such file"),
        ({}, "exactly one of policy"),
        ({"policy": NEAREST, "onnx": "x.onnx"}, "got policy and onnx"),
        ({"policy": NEAREST, "crop": 2}, "crop"),
    ],
)
def test_a_bad_policy_names_the_file_and_field(
    tmp_path: Path, params: dict[str, Any], message: str
) -> None:
    path = policy_scenario(tmp_path, **params)
    with pytest.raises(ScenarioError, match=message) as caught:
        load_scenario(path)
    assert str(path) in str(caught.value) and "team.strategy" in str(caught.value)
