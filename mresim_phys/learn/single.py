"""The Gymnasium environment (learning interface): one learning robot, its teammates on
their scenario's strategies.

``MresimEnv(scenarios, **options)`` (options: ``config.EnvConfig``'s fields; ``learner``
names the learning robot, by default the first of the first scenario). One environment step
is one decision of the learner: the simulation steps on, the teammates deciding as their
strategies do, until the learner is asked again (``stepping.asked``) or the episode ends;
the reward is summed over those steps. ``terminated`` when the learner fails or the run
stops on a rule other than its step cap; ``truncated`` at the step cap (or a stall). It is
picklable by construction, so ``gymnasium.vector.AsyncVectorEnv`` runs copies in worker
processes.
"""

from __future__ import annotations

from typing import Any

import gymnasium
import numpy as np

from mresim_phys.learn.common import configured, episode_choice, frame, possible_robots
from mresim_phys.learn.spaces import action_space, observation_space
from mresim_phys.learn.stepping import Episode, Outcome
from mresim_phys.strategies.policy.observe import Observation


class MresimEnv(gymnasium.Env[Observation, Any]):
    """One learning robot in a scenario (module docstring)."""

    metadata = {"render_modes": ["rgb_array"]}  # noqa: RUF012 (Gymnasium's attribute)

    def __init__(self, scenarios: Any, **options: Any) -> None:
        self.config, self.params = configured("MresimEnv", scenarios, options)
        self.learner = self.config.learner or possible_robots(self.config)[0]
        self.observation_space = observation_space(self.params)  # type: ignore[assignment]
        self.action_space = action_space(self.params)
        self.render_mode = self.config.render_mode
        self.episode: Episode | None = None

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Observation, dict[str, Any]]:
        """A new episode of ``seed`` (else drawn from the environment's generator), the
        learner at its first decision."""
        super().reset(seed=seed)
        episode_seed = seed if seed is not None else int(self.np_random.integers(2**31 - 1))
        choice = episode_choice(self.config, episode_seed, options)
        self.episode = Episode(self.config, choice, self.learner)
        self.on_to_decision(Outcome())
        return self.episode.observation(self.learner), self.info()

    def step(self, action: Any) -> tuple[Observation, float, bool, bool, dict[str, Any]]:
        """The learner's decision, then the steps up to its next one (module docstring)."""
        episode = self.live_episode()
        outcome = episode.advance({self.learner: action})
        outcome = self.on_to_decision(outcome)
        name = self.learner
        return (
            episode.observation(name), outcome.rewards.get(name, 0.0),
            outcome.terminated.get(name, False), outcome.truncated.get(name, False), self.info(),
        )  # fmt: skip

    def on_to_decision(self, outcome: Outcome) -> Outcome:
        """Step on while the learner is in the episode and not asked; ``outcome`` with
        those steps' folded in."""
        episode = self.live_episode()
        while self.learner in episode.live and not episode.asked(self.learner):
            outcome.add(episode.advance({}))
        return outcome

    def info(self) -> dict[str, Any]:
        """The step, the episode's scenario and failures, and why the run stopped."""
        episode = self.live_episode()
        return {
            "step": episode.sim.t, "scenario": str(episode.choice.scenario),
            "failures": episode.choice.failures, "stop": episode.over,
            "explored": episode.sim.record.explored,
            "known_at_base": episode.sim.record.known_at_base,
        }  # fmt: skip

    def render(self) -> np.ndarray | None:
        """The current frame (``render_mode='rgb_array'``), else None."""
        if self.render_mode != "rgb_array":
            return None
        return frame(self.live_episode())

    def live_episode(self) -> Episode:
        """The episode of the last reset."""
        if self.episode is None:
            raise RuntimeError("call reset() before step()")
        return self.episode
