"""Train a policy robot with PPO, then compare it with ``frontier`` under robot failures.

The learning robot explores ``examples/learn_small_rooms.yaml`` alone; its action is a slot
of its candidate table (frontiers nearest first, meetings, the base), its reward the cells it
newly knows less a time cost (docs/learning.md). The policy sees the candidate table, the
action mask and its own state (``FilterObservation``). Steps:

1. the mean return of a random valid choice and of the untrained network, over ``--eval``
   seeds;
2. PPO (stable-baselines3) for ``--timesteps`` decisions, the mean return of each batch of
   episodes written to ``OUT/curve.csv`` (and ``OUT/curve.png`` with matplotlib);
3. the trained policy's mean return over the same seeds (its greedy action);
4. the policy exported to ``OUT/policy.onnx`` and, with ``--study``, a robustness study
   (``OUT/study.yaml``: ``frontier`` and the ``policy`` strategy running that file, 0 and 1
   robot failures) run as ``mresim sweep`` runs it.

Run: ``pip install -e ".[train]"`` then ``python examples/train_ppo.py --out runs/ppo``
(about 3 minutes on 2 cores with the defaults).
"""

from __future__ import annotations

import argparse
import csv
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import torch
import yaml
from gymnasium.wrappers import FilterObservation
from stable_baselines3 import PPO
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.monitor import Monitor

from mresim_phys.learn.single import MresimEnv

HERE = Path(__file__).resolve().parent
SCENARIO = HERE / "learn_small_rooms.yaml"
KEYS = ["action_mask", "candidates", "own"]  # what the policy sees
POLICY = {"replan_interval": 10}


def make_env() -> Any:
    """The learning environment, its observation cut to ``KEYS``."""
    return FilterObservation(MresimEnv(str(SCENARIO), policy=POLICY), KEYS)


def mean_return(env: Any, act: Any, seeds: range) -> float:
    """The mean return of ``act`` (observation -> action) over ``seeds``."""
    returns = []
    for seed in seeds:
        obs, _ = env.reset(seed=seed)
        total, done = 0.0, False
        while not done:
            obs, reward, terminated, truncated, _ = env.step(act(obs))
            total, done = total + float(reward), terminated or truncated
        returns.append(total)
    return float(np.mean(returns))


class Curve(BaseCallback):
    """Each finished episode's return, as PPO trains."""

    def __init__(self) -> None:
        super().__init__()
        self.rows: list[tuple[int, float]] = []

    def _on_step(self) -> bool:
        for info in self.locals.get("infos", []):
            if "episode" in info:
                self.rows.append((self.num_timesteps, float(info["episode"]["r"])))
        return True


class Logits(torch.nn.Module):
    """The trained policy's slot scores from the observation's arrays (for ONNX)."""

    def __init__(self, model: PPO) -> None:
        super().__init__()
        self.policy = model.policy

    def forward(self, action_mask: Any, candidates: Any, own: Any) -> Any:
        obs = {"action_mask": action_mask, "candidates": candidates, "own": own}
        features = self.policy.extract_features(obs, self.policy.pi_features_extractor)
        latent = self.policy.mlp_extractor.forward_actor(features)
        return self.policy.action_net(latent)


def export(model: PPO, path: Path) -> None:
    """The policy's slot scores as an ONNX model whose inputs are named after ``KEYS``."""
    space = model.observation_space
    sample = tuple(torch.zeros((1, *space[k].shape), dtype=torch.float32) for k in KEYS)
    torch.onnx.export(
        Logits(model), sample, str(path), input_names=KEYS, output_names=["scores"], dynamo=False
    )


def study(out: Path, onnx: Path, seeds: int) -> Path:
    """A robustness study: frontier and the trained policy, 0 and 1 robot failures."""
    data = {
        "name": "ppo-robustness",
        "scenarios": [str(HERE / "learn_small_rooms_team.yaml")],
        "axes": {
            "team.strategy": [
                "frontier",
                {"name": "policy", "params": {"onnx": str(onnx.resolve()), **POLICY}},
            ],
            "failures": [0, 1],
        },
        "seeds": seeds,
    }
    path = out / "study.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return path


def main() -> None:
    """Train, evaluate, export, and compare (module docstring)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--timesteps", type=int, default=12_000)
    parser.add_argument("--eval", type=int, default=8, help="evaluation seeds")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=Path("runs/ppo"))
    parser.add_argument("--study", type=int, default=0, help="seeds of the robustness study")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    torch.set_num_threads(1)
    env, seeds = make_env(), range(1000, 1000 + args.eval)
    rng = np.random.default_rng(args.seed)
    random_valid = mean_return(env, lambda o: rng.choice(np.flatnonzero(o["action_mask"])), seeds)
    model = PPO("MultiInputPolicy", Monitor(make_env()), n_steps=256, batch_size=64,
                learning_rate=1e-3, ent_coef=0.01, seed=args.seed, verbose=0)  # fmt: skip
    untrained = mean_return(env, lambda o: model.predict(o, deterministic=True)[0], seeds)
    curve = Curve()
    model.learn(total_timesteps=args.timesteps, callback=curve)
    trained = mean_return(env, lambda o: model.predict(o, deterministic=True)[0], seeds)
    write_curve(args.out, curve.rows, random_valid)
    export(model, args.out / "policy.onnx")
    print(f"mean return over {args.eval} seeds: random valid choice {random_valid:.2f},"
          f" untrained {untrained:.2f}, trained {trained:.2f}")  # fmt: skip
    print(f"policy: {args.out / 'policy.onnx'}; curve: {args.out / 'curve.csv'}")
    if args.study:
        path = study(args.out, args.out / "policy.onnx", args.study)
        command = [sys.executable, "-m", "mresim_phys.cli", "sweep", str(path)]
        subprocess.run([*command, "--out", str(args.out / "study")], check=True)


def write_curve(out: Path, rows: list[tuple[int, float]], baseline: float) -> None:
    """The episodes' returns as PPO trained (CSV, and a PNG if matplotlib is installed)."""
    with (out / "curve.csv").open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(["timesteps", "episode_return"])
        writer.writerows(rows)
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return
    steps, returns = np.array(rows).T if rows else (np.zeros(0), np.zeros(0))
    window = max(1, len(returns) // 20)
    smooth = np.convolve(returns, np.ones(window) / window, mode="valid")
    fig, ax = plt.subplots(figsize=(6, 3.5))
    ax.plot(steps, returns, ".", alpha=0.3, label="episode return")
    ax.plot(steps[window - 1 :], smooth, label=f"mean of {window}")
    ax.axhline(baseline, color="grey", linestyle="--", label="random valid choice")
    ax.set_xlabel("decisions trained on")
    ax.set_ylabel("return")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out / "curve.png", dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    main()
