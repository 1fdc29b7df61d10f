"""Benchmark of the learning interface (issue 35): environment steps per second, and what the
interface costs over a bare simulation step.

The office (``scenarios/02_office_frontier.yaml``, 4 robots):

* **Steps per second** of the Gymnasium environment (robot A learns, B-D explore with
  ``frontier``; an environment step is one decision of A, the random valid choice) with 1 and
  with 2 vectorised workers (``SyncVectorEnv`` of 1, ``AsyncVectorEnv`` of 2): environment
  steps and simulation steps per second, over ``--seconds`` after a reset.
* **Overhead**: the PettingZoo environment, every robot a policy robot answered by the
  reference policy ``nearest_frontier``, against the bare simulation of the same scenario
  with the ``policy`` strategy running that policy itself: the same decisions, so the same
  run (checked at the end). Median ms per simulation step over ``--steps`` steps, the two
  stepped in turn (interleaved rounds), with ``skip_idle`` (the default: observations only
  at steps where some robot is asked) and without (every step). The bar: <= 1.2.

Run from the repository root: ``python benchmarks/bench_learn.py [--rounds 3]``.
"""

from __future__ import annotations

import argparse
import statistics
from pathlib import Path
from time import perf_counter
from typing import Any

import gymnasium
import numpy as np
import yaml

from mresim_phys.learn.parallel import MresimParallelEnv
from mresim_phys.learn.single import MresimEnv
from mresim_phys.scenario.load import load_scenario
from mresim_phys.sim import Simulation
from mresim_phys.strategies.policy.reference import nearest_frontier

ROOT = Path(__file__).resolve().parent.parent
OFFICE = ROOT / "scenarios" / "02_office_frontier.yaml"
NEAREST = "mresim_phys.strategies.policy.reference:nearest_frontier"
BAR = 1.2


def make_single() -> MresimEnv:
    """Robot A learns on the office; its teammates explore with frontier."""
    return MresimEnv(str(OFFICE), learner="A")


def vector_rate(workers: int, seconds: float) -> tuple[float, float]:
    """(environment steps, simulation steps) per second of ``workers`` vectorised envs."""
    maker = [make_single] * workers
    envs: Any = (
        gymnasium.vector.AsyncVectorEnv(maker)
        if workers > 1
        else gymnasium.vector.SyncVectorEnv(maker)
    )
    rng = np.random.default_rng(0)
    try:
        obs, infos = envs.reset(seed=list(range(workers)))
        steps, sim_steps, started = 0, 0, perf_counter()
        first = infos["step"].copy()
        while perf_counter() - started < seconds:
            masks = obs["action_mask"]
            actions = np.array([rng.choice(np.flatnonzero(m)) for m in masks])
            obs, _, _, _, infos = envs.step(actions)
            steps += workers
            sim_steps += int(np.maximum(infos["step"] - first, 0).sum())
            first = infos["step"].copy()
        elapsed = perf_counter() - started
    finally:
        envs.close()
    return steps / elapsed, sim_steps / elapsed


def bare_scenario(folder: Path) -> Path:
    """The office with every robot a policy robot running ``nearest_frontier`` itself."""
    data = yaml.safe_load(OFFICE.read_text())
    data["map"]["image"] = str((OFFICE.parent / data["map"]["image"]).resolve())
    data["team"]["strategy"] = {"name": "policy", "params": {"policy": NEAREST}}
    path = folder / "office_policy.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def overhead(
    steps: int, rounds: int, skip_idle: bool, folder: Path
) -> tuple[list[float], list[float]]:
    """Per round, ms per simulation step of the environment and of the bare simulation."""
    env_ms, bare_ms = [], []
    for _ in range(rounds):
        env = MresimParallelEnv(str(OFFICE), skip_idle=skip_idle, steps=steps)
        bare = Simulation(load_scenario(bare_scenario(folder)))
        obs, _ = env.reset(seed=7)  # the scenario's own seed
        env_time = bare_time = 0.0
        while env.agents:
            started = perf_counter()
            obs, *_ = env.step({a: nearest_frontier(obs[a]) for a in env.agents})
            env_time += perf_counter() - started
            target = env.live_episode().sim.t
            started = perf_counter()
            while bare.t < target and not bare.finished():
                bare.step()
            bare_time += perf_counter() - started
        sim = env.live_episode().sim
        assert sim.record == bare.record, "the environment's run differs from the bare run"
        env_ms.append(1e3 * env_time / sim.t)
        bare_ms.append(1e3 * bare_time / bare.t)
    return env_ms, bare_ms


def main() -> None:
    """Print the rates and the overhead ratios."""
    import tempfile

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--steps", type=int, default=300)
    parser.add_argument("--seconds", type=float, default=30.0)
    args = parser.parse_args()
    for workers in (1, 2):
        env_rate, sim_rate = vector_rate(workers, args.seconds)
        print(f"office, 4 robots, {workers} worker(s): {env_rate:6.1f} env steps/s,"
              f" {sim_rate:6.1f} simulation steps/s")  # fmt: skip
    with tempfile.TemporaryDirectory() as folder:
        for skip in (True, False):
            env_ms, bare_ms = overhead(args.steps, args.rounds, skip, Path(folder))
            env, bare = statistics.median(env_ms), statistics.median(bare_ms)
            shown = " / ".join(f"{e / b:.2f}" for e, b in zip(env_ms, bare_ms, strict=True))
            print(
                f"overhead, skip_idle={skip}: environment {env:6.2f} ms, bare {bare:6.2f} ms"
                f" per simulation step, x{env / bare:.2f} (bar <= {BAR}; rounds {shown})"
            )


if __name__ == "__main__":
    main()
