"""One episode's scenario (learning interface, input): chosen from named streams of its seed.

``reset(seed)`` draws, from the stream ``learn-episode`` of the seed (``rng.Streams``), the
scenario file, the team size and the number of failures (the curriculum's k). The scenario's
own seed becomes the episode's seed, its failures the ``failures`` axis of a sweep gives
(``sweeps/failures.py``: k robots fail at the seed's random steps within the failure
window), its team is resized as ``robots.count`` resizes it (``sweeps/placement.py``), and
the policy robots get the ``policy`` strategy, its decisions from the environment. Same
seed and configuration: the same scenario, and so the same episode.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mresim_phys.errors import MresimError
from mresim_phys.learn.config import EnvConfig
from mresim_phys.rng import Streams
from mresim_phys.scenario.load import (
    check_own_values,
    resolve_map_path,
    resolve_mask_paths,
    validate_scenario,
)
from mresim_phys.scenario.readers import read_yaml_mapping
from mresim_phys.scenario.schema import Scenario
from mresim_phys.sweeps.failures import with_failures
from mresim_phys.sweeps.placement import resize_team

STREAM = "learn-episode"


@dataclass(frozen=True)
class EpisodeChoice:
    """What an episode's seed chose."""

    scenario: Path
    robots: int | None
    failures: int
    seed: int


def choose(config: EnvConfig, seed: int) -> EpisodeChoice:
    """The episode of ``seed``: its scenario, team size and failures, from stream ``STREAM``."""
    rng = Streams(seed).get(STREAM)
    scenario = config.scenarios[int(rng.integers(len(config.scenarios)))]
    robots = None
    if config.robots is not None:
        robots = config.robots[int(rng.integers(len(config.robots)))]
    failures = config.failures[int(rng.integers(len(config.failures)))]
    return EpisodeChoice(scenario, robots, failures, seed)


def base_data(path: Path) -> dict[str, Any]:
    """A scenario file's data, its own values checked."""
    data = read_yaml_mapping(path)
    check_own_values(data, str(path))
    return data


def episode_scenario(
    config: EnvConfig, choice: EpisodeChoice, learners: str | None
) -> tuple[Scenario, list[str]]:
    """The scenario of ``choice`` and its robots' names; ``learners``: the one robot that
    learns (None: every robot)."""
    path = choice.scenario
    source = str(path)
    data = copy.deepcopy(base_data(path))
    data["seed"] = choice.seed
    if config.steps is not None:
        data["steps"] = config.steps
    if config.faults is not None:
        data["faults"] = copy.deepcopy(config.faults)
    folder = path.resolve().parent
    if choice.robots is not None:
        located = resolve_map_path(validate_scenario(data, source, folder), folder, source)
        data = resize_team(data, located, choice.robots, source)
    names = [str(r["name"]) for r in data.get("robots") or []]
    steps = int(validate_scenario(data, source, folder).steps)
    data = with_failures(
        data, names, choice.failures, choice.seed, steps, config.failure_window, source
    )
    data = with_policy(data, config.policy, learners, source)
    scenario = validate_scenario(data, source, folder)
    return resolve_mask_paths(resolve_map_path(scenario, folder, source), folder, source), names


def with_policy(
    data: dict[str, Any], params: dict[str, Any], learner: str | None, source: str
) -> dict[str, Any]:
    """``data`` with the ``policy`` strategy, decided by the environment, for ``learner``
    (None: every robot)."""
    strategy = {"name": "policy", "params": {**params, "external": True}}
    robots = [dict(r) for r in data.get("robots") or []]
    names = [r.get("name") for r in robots]
    if learner is not None and learner not in names:
        raise MresimError(
            f"{source}: learner {learner!r} is not a robot of this scenario ({names})"
        )
    for robot in robots:
        if learner is None or robot.get("name") == learner:
            robot["strategy"] = copy.deepcopy(strategy)
    return {**data, "robots": robots}
