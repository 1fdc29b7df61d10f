"""What both environments share (learning interface): the configuration and policy
parameters validated, the robots an environment may have, episodes chosen by seed and
options, frames."""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from pydantic import ValidationError

from mresim_phys.errors import MresimError
from mresim_phys.learn.config import EnvConfig, described, env_config
from mresim_phys.learn.episode import EpisodeChoice, base_data, choose
from mresim_phys.learn.stepping import Episode
from mresim_phys.render.frame import Renderer
from mresim_phys.render.layers import parse_layers
from mresim_phys.scenario.load import resolve_map_path, validate_scenario
from mresim_phys.strategies.params import PolicyParams
from mresim_phys.sweeps.placement import resize_team

OPTIONS = ("scenario", "robots", "failures")  # what reset(options=...) may fix


def configured(
    kind: str, scenarios: Any, options: Mapping[str, Any]
) -> tuple[EnvConfig, PolicyParams]:
    """The configuration and the policy robots' parameters (MresimError naming the field)."""
    config = env_config(kind, scenarios=scenarios, **options)
    try:
        params = PolicyParams.model_validate({**config.policy, "external": True})
    except ValidationError as exc:
        raise MresimError(f"{kind}: policy: {described(exc)} (docs/learning.md)") from None
    return config, params


def possible_robots(config: EnvConfig) -> list[str]:
    """Every robot an episode may have: each scenario's team at the largest size drawn,
    in order of first appearance."""
    names: list[str] = []
    for path in config.scenarios:
        data = base_data(path)
        if config.robots is not None:
            source, folder = str(path), path.resolve().parent
            scenario = validate_scenario(data, source, folder)
            located = resolve_map_path(scenario, folder, source)
            data = resize_team(data, located, max(config.robots), source)
        names += [str(r["name"]) for r in data.get("robots") or [] if str(r["name"]) not in names]
    return names


def episode_choice(
    config: EnvConfig, seed: int, options: Mapping[str, Any] | None
) -> EpisodeChoice:
    """The episode of ``seed``, with what ``options`` fix (``scenario``: an index into the
    scenarios, ``robots``, ``failures``)."""
    choice = choose(config, seed)
    given = dict(options or {})
    unknown = sorted(set(given) - set(OPTIONS))
    if unknown:  # Gymnasium's rule: an environment ignores options it does not know
        warnings.warn(
            f"reset options {unknown} are ignored; this environment knows {list(OPTIONS)}",
            stacklevel=3,
        )
    scenario = choice.scenario
    if "scenario" in given:
        index = int(given["scenario"])
        if not 0 <= index < len(config.scenarios):
            count = len(config.scenarios)
            raise MresimError(f"reset options: scenario {index} is not an index of {count}")
        scenario = config.scenarios[index]
    robots = given.get("robots", choice.robots)
    failures = int(given.get("failures", choice.failures))
    return EpisodeChoice(Path(scenario), None if robots is None else int(robots), failures, seed)


def frame(episode: Episode) -> np.ndarray:
    """The episode's current frame, RGB (height, width, 3) uint8, every layer drawn."""
    sim = episode.sim
    image = Renderer(sim.world.occupied.shape, parse_layers("all")).render(sim.snapshot())
    return np.ascontiguousarray(image[:, :, ::-1])
