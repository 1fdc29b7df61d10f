"""The learning interface (``mresim_phys/learn``): the PettingZoo and Gymnasium environments
pass their ecosystems' own checks, ask a robot exactly when the simulation would ask its
strategy (clocks included), take robots that fail out, pay the documented rewards, and give
the same episode for the same seed, in any process."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import gymnasium
import numpy as np
import pytest
import yaml
from pettingzoo.test import parallel_api_test, parallel_seed_test

from mresim_phys.errors import MresimError
from mresim_phys.learn.parallel import MresimParallelEnv
from mresim_phys.learn.rewards import known_cells
from mresim_phys.learn.single import MresimEnv
from mresim_phys.strategies.policy.reference import nearest_frontier

SCENARIOS = Path(__file__).resolve().parent.parent / "scenarios"
QUICKSTART = str(SCENARIOS / "01_quickstart.yaml")
NEAREST = "mresim_phys.strategies.policy.reference:nearest_frontier"


def with_team(tmp_path: Path, **team: Any) -> str:
    """The quickstart scenario with ``team`` fields added, written beside the test."""
    data = yaml.safe_load(Path(QUICKSTART).read_text())
    data["map"]["image"] = str((SCENARIOS / data["map"]["image"]).resolve())
    data["team"].update(team)
    path = tmp_path / "scenario.yaml"
    path.write_text(yaml.safe_dump(data))
    return str(path)


def test_the_parallel_env_passes_pettingzoos_checks() -> None:
    with pytest.warns(UserWarning, match="ignored"):  # the check passes an unknown option
        parallel_api_test(MresimParallelEnv(QUICKSTART, steps=40), num_cycles=60)
    parallel_seed_test(lambda: MresimParallelEnv(QUICKSTART, steps=40), num_cycles=40)


def test_the_single_env_passes_gymnasiums_check() -> None:
    from gymnasium.utils.env_checker import check_env

    check_env(MresimEnv(QUICKSTART, steps=40), skip_render_check=True)


def play(env: Any, seed: int, decisions: int) -> list[Any]:
    """Observations and rewards of ``decisions`` nearest-frontier decisions from ``seed``."""
    obs, _ = env.reset(seed=seed)
    seen = [obs]
    for _ in range(decisions):
        obs, reward, terminated, truncated, _ = env.step(nearest_frontier(obs))
        seen += [obs, reward]
        if terminated or truncated:
            break
    return seen


def test_same_seed_same_episode_in_a_worker_process() -> None:
    vector = gymnasium.vector.AsyncVectorEnv([lambda: MresimEnv(QUICKSTART)] * 2)
    try:
        obs, _ = vector.reset(seed=[5, 6])
        local = MresimEnv(QUICKSTART)
        first, _ = local.reset(seed=6)
        for key, value in first.items():
            assert np.array_equal(obs[key][1], value)
        for _ in range(4):
            action = nearest_frontier(first)
            obs, rewards, *_ = vector.step(np.array([action, action]))
            first, reward, *_ = local.step(action)
            assert rewards[1] == reward
            assert all(np.array_equal(obs[k][1], v) for k, v in first.items())
    finally:
        vector.close()
    again = play(MresimEnv(QUICKSTART), 3, 6)
    for a, b in zip(play(MresimEnv(QUICKSTART), 3, 6), again, strict=True):
        if isinstance(a, dict):
            assert all(np.array_equal(a[k], b[k]) for k in a)
        else:
            assert a == b


def asks_of(env: MresimParallelEnv, steps: int) -> dict[str, list[int]]:
    """The steps each robot was asked on, acting on every ask (no steps skipped)."""
    obs, infos = env.reset(seed=1)
    asked: dict[str, list[int]] = {a: [] for a in env.possible_agents}
    for _ in range(steps):
        if not env.agents:
            break
        episode = env.live_episode()
        actions = {}
        for agent in env.agents:
            mask = obs[agent]["action_mask"]
            if infos[agent]["asked"]:
                asked[agent].append(episode.sim.t)
                assert mask.sum() >= 1
                actions[agent] = nearest_frontier(obs[agent])
            else:
                assert mask.tolist() == [1] + [0] * (len(mask) - 1)  # only continue
                actions[agent] = len(mask) - 1  # the base: ignored
        before = {a: episode.strategy(a).target for a in env.agents}
        obs, _, _, _, infos = env.step(actions)
        for agent, action in actions.items():
            robot = episode.learners[agent]
            if (action == len(obs[agent]["action_mask"]) - 1 and agent not in asked) or (
                asked[agent] and asked[agent][-1] != episode.sim.t - 1
            ):
                assert robot.last_plan_step != episode.sim.t - 1 or before[agent] is not None
    return asked


def test_a_robot_is_asked_when_its_strategy_would_be_and_its_clock_allows(tmp_path: Path) -> None:
    env = MresimParallelEnv(with_team(tmp_path, clock={"decision_period": 7}), skip_idle=False)
    asked = asks_of(env, 80)
    for steps in asked.values():
        assert len(steps) >= 3
        assert min(np.diff(steps)) >= 7
    env = MresimParallelEnv(with_team(tmp_path, clock={"act_every": 3}), skip_idle=False)
    for steps in asks_of(env, 60).values():
        assert steps and all(s % 3 == 0 for s in steps)


def test_an_asked_robots_action_is_followed_and_others_are_ignored() -> None:
    env = MresimParallelEnv(QUICKSTART, skip_idle=False, policy={"replan_interval": 50})
    obs, infos = env.reset(seed=2)
    episode = env.live_episode()
    assert all(infos[a]["asked"] for a in env.agents)  # nobody has a plan at the start
    obs, *_, infos = env.step({a: nearest_frontier(obs[a]) for a in env.agents})
    targets = {a: episode.strategy(a).target for a in env.agents}
    idle = [a for a in env.agents if not infos[a]["asked"]]
    assert idle
    env.step(dict.fromkeys(env.agents, 1))  # slot 1 for everyone: only the asked take it
    for agent in idle:
        if not infos[agent]["asked"]:
            assert episode.strategy(agent).target == targets[agent]


def test_a_robot_that_fails_leaves_and_pays_the_failure_cost() -> None:
    env = MresimParallelEnv(
        QUICKSTART, failures=(1,), failure_window=(0.05, 0.1), steps=100,
        rewards={"failure": 7.0},
    )  # fmt: skip
    obs, _ = env.reset(seed=4)
    gone: dict[str, float] = {}
    while env.agents:
        before = list(env.agents)
        obs, rewards, terminated, _, _ = env.step({a: nearest_frontier(obs[a]) for a in env.agents})
        for agent in before:
            if terminated[agent] and env.live_episode().over is None:
                gone[agent] = rewards[agent]
                assert agent not in env.agents
    assert len(gone) == 1
    ((name, paid),) = gone.items()
    assert paid <= -7.0 + 1.0
    robot = next(r for r in env.live_episode().sim.robots if r.name == name)
    assert not robot.alive and robot.strategy is not None and robot.strategy.name == "frontier"


def test_the_reward_is_its_weighted_components() -> None:
    weights = {"explored_own": 1.0, "explored_team": 0.0, "known_at_base": 0.0, "time": 0.5}
    env = MresimParallelEnv(QUICKSTART, rewards=weights, skip_idle=False)
    obs, _ = env.reset(seed=0)
    episode = env.live_episode()
    for _ in range(10):
        known = {a: known_cells(episode.learners[a].belief) for a in env.agents}
        obs, rewards, *_ = env.step({a: nearest_frontier(obs[a]) for a in env.agents})
        for agent, value in rewards.items():
            gained = known_cells(episode.learners[agent].belief) - known[agent]
            assert value == pytest.approx(gained - 0.5)


def test_the_step_cap_truncates_and_reset_options_fix_the_episode() -> None:
    env = MresimParallelEnv(QUICKSTART, steps=30, robots=(1, 2, 3))
    assert len(env.possible_agents) == 3
    env.reset(seed=0, options={"robots": 1})
    assert len(env.agents) == 1
    last: tuple[dict[str, bool], dict[str, bool]] = ({}, {})
    while env.agents:
        _, _, terminated, truncated, _ = env.step(dict.fromkeys(env.agents, 0))
        last = (terminated, truncated)
    assert all(last[1].values()) and not any(last[0].values())
    assert env.live_episode().sim.t == 30
    assert env.state_space.contains(env.state())
    frame = MresimParallelEnv(QUICKSTART, render_mode="rgb_array")
    frame.reset(seed=0)
    image = frame.render()
    assert image is not None and image.ndim == 3 and image.shape[2] == 3


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"stepz": 3}, "stepz"),
        ({"failure_window": (0.5, 0.2)}, "failure_window"),
        ({"policy": {"frontiers": 0}}, "policy: frontiers"),
        ({"policy": {"action": "teleport"}}, "policy: action"),
        ({"robots": (0, 2)}, "robots: .*team sizes >= 1"),
        ({"failures": (-1,)}, "failures: .*counts >= 0"),
    ],
)
def test_a_bad_configuration_names_its_field(options: dict[str, Any], message: str) -> None:
    with pytest.raises(MresimError, match=message):
        MresimParallelEnv(QUICKSTART, **options)


def test_goal_and_velocity_actions_step_the_robot() -> None:
    for action, sample in (("goal_cell", [0.9, 0.5]), ("velocity", [0.0, 1.0])):
        env = MresimEnv(QUICKSTART, policy={"action": action}, steps=20)
        env.reset(seed=0)
        start = env.live_episode().learners["A"].position
        for _ in range(5):
            env.step(np.array(sample, dtype=np.float32))
        assert env.live_episode().learners["A"].position[0] > start[0] + 3


def test_the_environments_run_is_the_run_with_the_policy_inside(tmp_path: Path) -> None:
    """The same decisions, with or without the learning wrapper: the same run."""
    from mresim_phys import Simulation
    from mresim_phys.scenario.load import load_scenario

    inside = with_team(tmp_path, strategy={"name": "policy", "params": {"policy": NEAREST}})
    bare = Simulation(load_scenario(inside))
    env = MresimParallelEnv(QUICKSTART)
    obs, _ = env.reset(seed=1)  # the scenario's own seed
    while env.agents:
        obs, *_ = env.step({a: nearest_frontier(obs[a]) for a in env.agents})
        sim = env.live_episode().sim
        while bare.record.step < sim.record.step:
            bare.step()
        assert bare.record == sim.record
    assert sim.record.step > 20


def test_a_policy_run_replays_as_it_ran(tmp_path: Path) -> None:
    from test_dynamic_render import assert_replay_equals_live

    scenario = with_team(tmp_path, strategy={"name": "policy", "params": {"policy": NEAREST}})
    assert_replay_equals_live(Path(scenario), tmp_path / "run", (10, 40))


def test_episodes_draw_maps_from_an_instance_sets_split(tmp_path: Path) -> None:
    from mresim_phys.cli import main

    spec = {
        "name": "tiny",
        "instances": [{"kind": "building", "size": [200, 140], "seeds": 3},
                      {"kind": "cave", "size": [160, 160], "seeds": 2}],
        "robots": 3, "radius": 2.0, "split": {"test": 0.4, "seed": 0},
    }  # fmt: skip
    (tmp_path / "spec.yaml").write_text(yaml.safe_dump(spec))
    assert main(["make-set", str(tmp_path / "spec.yaml"), "--out", str(tmp_path / "maps")]) == 0
    index = yaml.safe_load((tmp_path / "maps" / "set.yaml").read_text())
    train = {i["id"] for i in index["instances"] if i["split"] == "train"}
    env = MresimParallelEnv(str(tmp_path / "maps"), split="train", steps=10, robots=(2, 3))
    assert {p.parent.name for p in env.config.scenarios} == train
    drawn = set()
    for seed in range(8):
        _, infos = env.reset(seed=seed)
        drawn.add(Path(next(iter(infos.values()))["scenario"]).parent.name)
        assert len(env.agents) in (2, 3)
    assert drawn <= train and len(drawn) > 1
    with pytest.raises(MresimError, match=r"without set\.yaml"):
        MresimParallelEnv(str(tmp_path))
    (tmp_path / "set.yaml").write_text(yaml.safe_dump(spec))  # a set's spec, not its index
    with pytest.raises(MresimError, match="not the index"):
        MresimParallelEnv(str(tmp_path))
