"""The PettingZoo environment (learning interface): every robot of a scenario a policy robot.

``MresimParallelEnv(scenarios, **options)`` (options: ``config.EnvConfig``'s fields).
``possible_agents`` are the robots an episode may have; ``agents`` the policy robots still in
it. Every step gives each of them an observation, and asks a decision only of those the step
asks (``observation["asked"]``; with choice actions the ``action_mask`` then leaves only
``continue`` to the others, whose actions are ignored). With ``skip_idle`` (the default) the
environment steps on until some robot is asked, its rewards summed over the steps skipped.
A robot that fails is terminated and leaves ``agents``; ``truncated`` at the step cap.
``state()`` is the privileged truth for centralised critics (``spaces.state_space``).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv

from mresim_phys.learn.common import configured, episode_choice, frame, possible_robots
from mresim_phys.learn.spaces import action_space, observation_space, state_space
from mresim_phys.learn.stepping import Episode, Outcome
from mresim_phys.strategies.policy.observe import Observation


class MresimParallelEnv(ParallelEnv[str, Observation, Any]):  # type: ignore[misc]
    """A scenario's team as PettingZoo agents (module docstring)."""

    metadata = {  # noqa: RUF012 (PettingZoo's attribute)
        "name": "mresim_v0", "render_modes": ["rgb_array"], "is_parallelizable": True,
    }  # fmt: skip

    def __init__(self, scenarios: Any, **options: Any) -> None:
        self.config, self.params = configured("MresimParallelEnv", scenarios, options)
        self.possible_agents = possible_robots(self.config)
        observation, action = observation_space(self.params), action_space(self.params)
        self.observation_spaces = dict.fromkeys(self.possible_agents, observation)
        self.action_spaces = dict.fromkeys(self.possible_agents, action)
        self.state_space = state_space(self.params.coarse, len(self.possible_agents))
        self.render_mode = self.config.render_mode
        self.agents: list[str] = []
        self.episode: Episode | None = None
        self._seeds = np.random.default_rng()

    def observation_space(self, agent: str) -> spaces.Space[Any]:
        """Agent ``agent``'s observation space."""
        return self.observation_spaces[agent]

    def action_space(self, agent: str) -> spaces.Space[Any]:
        """Agent ``agent``'s action space."""
        return self.action_spaces[agent]

    def reset(
        self, seed: int | None = None, options: Mapping[str, Any] | None = None
    ) -> tuple[dict[str, Observation], dict[str, dict[str, Any]]]:
        """A new episode: of ``seed`` (else the next of the environment's seeds), its
        scenario, team size and failures drawn or fixed by ``options``."""
        if seed is not None:
            self._seeds = np.random.default_rng(seed)
        episode_seed = seed if seed is not None else int(self._seeds.integers(2**31 - 1))
        self.episode = Episode(
            self.config, episode_choice(self.config, episode_seed, options), None
        )
        self.skip()
        self.agents = list(self.episode.live)
        return self.observations(self.agents), {a: self.info(a) for a in self.agents}

    def step(
        self, actions: Mapping[str, Any]
    ) -> tuple[
        dict[str, Observation], dict[str, float], dict[str, bool], dict[str, bool],
        dict[str, dict[str, Any]],
    ]:  # fmt: skip
        """Close the step with ``actions`` (module docstring)."""
        episode = self.live_episode()
        present = list(self.agents)
        outcome = episode.advance(actions)
        outcome.add(self.skip())
        self.agents = list(episode.live)
        rewards = {a: outcome.rewards.get(a, 0.0) for a in present}
        terminated = {a: outcome.terminated.get(a, False) for a in present}
        truncated = {a: outcome.truncated.get(a, False) for a in present}
        return (
            self.observations(present),
            rewards,
            terminated,
            truncated,
            {a: self.info(a) for a in present},
        )

    def skip(self) -> Outcome:
        """With ``skip_idle``, step on until some robot is asked or the episode ends; the
        outcome of the steps skipped."""
        episode = self.live_episode()
        outcome = Outcome()
        while self.config.skip_idle and episode.live and not episode.anyone_asked():
            outcome.add(episode.advance({}))
        return outcome

    def observations(self, names: list[str]) -> dict[str, Observation]:
        """The observations of ``names``."""
        episode = self.live_episode()
        return {name: episode.observation(name) for name in names}

    def info(self, name: str) -> dict[str, Any]:
        """What a step tells of robot ``name`` besides its observation."""
        episode = self.live_episode()
        return {
            "asked": episode.asked(name), "step": episode.sim.t,
            "scenario": str(episode.choice.scenario), "failures": episode.choice.failures,
            "stop": episode.over,
        }  # fmt: skip

    def state(self) -> np.ndarray:
        """The privileged state now (``spaces.state_space``)."""
        return self.live_episode().state_vector(self.params.coarse, self.possible_agents)

    def render(self) -> np.ndarray | None:
        """The current frame (``render_mode='rgb_array'``), else None."""
        if self.render_mode != "rgb_array":
            return None
        return frame(self.live_episode())

    def close(self) -> None:
        """Nothing to release."""

    def live_episode(self) -> Episode:
        """The episode of the last reset."""
        if self.episode is None:
            raise RuntimeError("call reset() before step()")
        return self.episode
