"""Environment configuration (learning interface, input): what a learning environment is
made of, validated like a scenario (unknown keys and bad values name the field)."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Literal

from pydantic import Field, ValidationError, field_validator

from mresim_phys.errors import MresimError
from mresim_phys.scenario.readers import read_yaml_mapping
from mresim_phys.strict import Strict


class RewardWeights(Strict):
    """Weights of the reward components (docs/learning.md): per cell, per step, per failure."""

    explored_own: float = Field(1e-3, description="Per cell newly known in the robot's own map.")
    explored_team: float = Field(0.0, description="Per cell the team newly explored.")
    known_at_base: float = Field(1e-3, description="Per cell newly known at the base station.")
    time: float = Field(0.01, description="Paid every step the robot is in the episode.")
    failure: float = Field(5.0, description="Paid once when the robot fails.")


class EnvConfig(Strict):
    """A learning environment (docs/learning.md)."""

    scenarios: tuple[Path, ...] = Field(
        min_length=1,
        description="Scenario files, or folders of instance sets (mresim make-set); each"
        " episode draws one.",
    )
    split: Literal["all", "train", "test"] = Field(
        "all", description="The instances of a set's split that episodes draw from."
    )
    robots: tuple[int, ...] | None = Field(
        None, description="Team sizes an episode draws from (default: each scenario's team)."
    )
    failures: tuple[int, ...] = Field(
        (0,), description="Robot failures an episode draws from (the curriculum's k)."
    )
    failure_window: tuple[float, float] = Field(
        (0.1, 0.5), description="The failures happen uniformly between these fractions of steps."
    )
    faults: dict[str, Any] | None = Field(
        None, description="A faults block (docs/faults.md) replacing the scenario's: a fault law."
    )
    steps: int | None = Field(None, ge=1, description="Step cap (default: the scenario's).")
    policy: dict[str, Any] = Field(
        default_factory=dict,
        description="The policy robots' parameters (the policy strategy's, but its source).",
    )
    rewards: RewardWeights = Field(default_factory=RewardWeights)
    learner: str | None = Field(
        None, description="The single-agent environment's learning robot (default: the first)."
    )
    fallback: str = Field(
        "frontier", description="The strategy a robot follows once it has left the episode."
    )
    skip_idle: bool = Field(
        True, description="Step on until some robot is asked (parallel environment)."
    )
    render_mode: Literal["rgb_array"] | None = None

    @field_validator("failure_window")
    @classmethod
    def _window(cls, value: tuple[float, float]) -> tuple[float, float]:
        if not 0.0 <= value[0] <= value[1] <= 1.0:
            raise ValueError("give two fractions 0 <= first <= second <= 1")
        return value

    @field_validator("robots")
    @classmethod
    def _sizes(cls, value: tuple[int, ...] | None) -> tuple[int, ...] | None:
        if value is not None and (not value or min(value) < 1):
            raise ValueError("give one or more team sizes >= 1")
        return value

    @field_validator("failures")
    @classmethod
    def _counts(cls, value: tuple[int, ...]) -> tuple[int, ...]:
        if not value or min(value) < 0:
            raise ValueError("give one or more counts >= 0")
        return value


def env_config(source: str, **given: Any) -> EnvConfig:
    """``given`` validated; a mistake is a :class:`~mresim_phys.errors.MresimError` naming
    ``source`` and the field."""
    if isinstance(given.get("scenarios"), (str, Path)):
        given["scenarios"] = (given["scenarios"],)
    try:
        config = EnvConfig.model_validate(given)
    except ValidationError as exc:
        raise MresimError(f"{source}: {described(exc)} (docs/learning.md)") from None
    files = [f for path in config.scenarios for f in scenario_files(path, config.split, source)]
    if not files:
        raise MresimError(f"{source}: scenarios: no {config.split} instance in {config.scenarios}")
    return config.model_copy(update={"scenarios": tuple(files)})


def scenario_files(path: Path, split: str, source: str) -> list[Path]:
    """``path`` if it is a scenario file; the instances of ``split`` of an instance set's
    folder (its ``set.yaml``: each instance's ``scenario.yaml``)."""
    if not path.is_dir():
        if not path.is_file():
            raise MresimError(f"{source}: scenarios: no such file or folder {path}")
        return [path]
    index_path = path / "set.yaml"
    if not index_path.is_file():
        raise MresimError(
            f"{source}: scenarios: {path} is a folder without set.yaml (an instance set"
            " written by mresim make-set); give scenario files or a set's folder"
        )
    index = read_yaml_mapping(index_path)
    instances = index.get("instances")
    if not isinstance(instances, list) or not all(
        isinstance(i, dict) and "id" in i for i in instances
    ):
        raise MresimError(
            f"{source}: scenarios: {index_path} is not the index mresim make-set writes"
            " (instances with an id each)"
        )
    chosen = [i for i in instances if split in ("all", i.get("split"))]
    return [path / str(i["id"]) / "scenario.yaml" for i in chosen]


def described(exc: ValidationError) -> str:
    """Every problem as ``field: what was wrong``, joined."""
    return "; ".join(
        f"{'.'.join(str(p) for p in e['loc']) or 'configuration'}:"
        f" {str(e['msg']).removeprefix('Value error, ')}"
        for e in exc.errors(include_url=False)
    )
