"""One episode at its decision points (learning interface, phase loop): a Simulation
stepped from one step's decide phase to the next's.

Between :meth:`~mresim_phys.sim.Simulation.open_step` (events, clocks) and
:meth:`~mresim_phys.sim.Simulation.close_step` (decide, move, sense, communicate, measure)
the episode knows which policy robots the step asks for a decision: exactly those whose
strategies the simulation would ask (:func:`asked`: the robot can move, its clock lets it
act and decide now, and its replan is due: ``clocks/gate.py``, ``motion.wants_plan``). Their
observations are built from the same view their strategy then sees, and the action given
for each is left as its strategy's ``answer``. A robot that is not asked may only continue.

A policy robot that fails leaves the episode: it is terminated and its strategy becomes the
configuration's ``fallback``, which it follows if it recovers. The episode ends, for every
robot, when the run stops: truncated at its step cap or when it stalls, terminated on any
other stop rule (``explored``, ``known_at_base``, ``all_done``).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import cv2
import numpy as np

from mresim_phys.agents import Robot
from mresim_phys.clocks.gate import acts, may_decide
from mresim_phys.learn.config import EnvConfig
from mresim_phys.learn.episode import EpisodeChoice, episode_scenario
from mresim_phys.learn.rewards import RewardState, known_cells, reward, team_gains
from mresim_phys.motion import wants_plan
from mresim_phys.sim import Simulation
from mresim_phys.strategies.catalog import STRATEGIES
from mresim_phys.strategies.policy.observe import Observation
from mresim_phys.strategies.policy.strategy import PolicyStrategy
from mresim_phys.types import UNKNOWN

TRUNCATING = ("steps", "stalled")  # stop reasons that cut an episode short


@dataclass
class Outcome:
    """What one environment step gave each policy robot still in the episode."""

    rewards: dict[str, float] = field(default_factory=dict)
    terminated: dict[str, bool] = field(default_factory=dict)
    truncated: dict[str, bool] = field(default_factory=dict)

    def add(self, other: Outcome) -> None:
        """Fold a later sub-step's outcome in (rewards summed, flags kept once set)."""
        for name, value in other.rewards.items():
            self.rewards[name] = self.rewards.get(name, 0.0) + value
        for flags, more in ((self.terminated, other.terminated), (self.truncated, other.truncated)):
            for name, flag in more.items():
                flags[name] = flags.get(name, False) or flag


class Episode:
    """One episode of a learning environment (module docstring)."""

    def __init__(self, config: EnvConfig, choice: EpisodeChoice, learner: str | None) -> None:
        scenario, self.names = episode_scenario(config, choice, learner)
        self.config, self.choice = config, choice
        self.sim = Simulation(scenario)
        self.learners = {
            r.name: r for r in self.sim.robots if isinstance(r.strategy, PolicyStrategy)
        }
        self.policies = {n: r.strategy for n, r in self.learners.items()}  # kept once they leave
        self.live = list(self.learners)  # in the team's order
        self.state = RewardState(
            self.sim.record.explored, self.sim.record.known_at_base,
            {n: known_cells(r.belief) for n, r in self.learners.items()},
        )  # fmt: skip
        self.over: str | None = self.sim.stop_reason()
        if self.over is None:
            self.sim.open_step()

    def strategy(self, name: str) -> PolicyStrategy:
        """The policy strategy of robot ``name``."""
        strategy = self.policies[name]
        assert isinstance(strategy, PolicyStrategy)
        return strategy

    def asked(self, name: str) -> bool:
        """Whether this step asks robot ``name`` for a decision (module docstring)."""
        robot = self.learners[name]
        if self.over is not None or name not in self.live or not robot.can_move or not acts(robot):
            return False
        interval = self.strategy(name).params.replan_interval
        return may_decide(robot, self.sim.t) and wants_plan(robot, self.sim.t, interval)

    def observation(self, name: str) -> Observation:
        """Robot ``name``'s observation now."""
        robot = self.learners[name]
        return self.strategy(name).observation(self.sim.view_of(robot), self.asked(name))

    def advance(self, actions: Mapping[str, Any]) -> Outcome:
        """Close the step with ``actions`` (for robots asked; others are ignored), measure
        the rewards, and open the next step unless the run stopped."""
        for name, action in actions.items():
            if name in self.learners and self.asked(name):
                self.strategy(name).answer = action
        record = self.sim.close_step()
        for name in self.learners:
            self.strategy(name).answer = None  # an answer is for this step only
        team, base = team_gains(self.state, record, self.sim.setup.free_area)
        outcome = Outcome()
        for name in list(self.live):
            robot = self.learners[name]
            failed = not robot.alive
            known = known_cells(robot.belief)
            own, self.state.known[name] = known - self.state.known[name], known
            weights = self.config.rewards
            outcome.rewards[name] = reward(weights, own, team, base, failed)
            outcome.terminated[name], outcome.truncated[name] = failed, False
            if failed:
                self.leave(robot)
        self.over = self.sim.stop_reason()
        if self.over is not None:
            for name in self.live:
                outcome.terminated[name] = self.over not in TRUNCATING
                outcome.truncated[name] = self.over in TRUNCATING
            self.live = []
        else:
            self.sim.open_step()
        return outcome

    def leave(self, robot: Robot) -> None:
        """A failed policy robot leaves the episode; the fallback strategy takes over."""
        self.live.remove(robot.name)
        robot.strategy = STRATEGIES.make(self.config.fallback)

    def anyone_asked(self) -> bool:
        """Whether some robot in the episode is asked now."""
        return any(self.asked(name) for name in self.live)

    def state_vector(self, side: int, possible: list[str]) -> np.ndarray:
        """The privileged state (``spaces.state_space``): true obstacles and the base's
        known cells shrunk to ``side`` x ``side``, then x, y, alive of each possible robot."""
        truth = self.sim.world.occupied.astype(np.float32)
        known = (self.sim.base.belief != UNKNOWN).astype(np.float32)
        rows, cols = truth.shape
        grids = [cv2.resize(g, (side, side), interpolation=cv2.INTER_AREA) for g in (truth, known)]
        robots = np.zeros((len(possible), 3), dtype=np.float32)
        by_name = {r.name: r for r in self.sim.robots}
        for k, name in enumerate(possible):
            robot = by_name.get(name)
            if robot is not None:
                x, y = robot.position
                robots[k] = (
                    min(max(x / cols, 0.0), 1.0),
                    min(max(y / rows, 0.0), 1.0),
                    robot.alive,
                )
        state = np.concatenate([g.reshape(-1) for g in grids] + [robots.reshape(-1)])
        return np.clip(state, 0.0, 1.0)  # the shrinking's float error kept within [0, 1]
