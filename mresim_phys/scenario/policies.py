"""Policy files (phase 0, input): the trained policies ``policy`` robots run, checked when
the scenario is read, as its map is.

A ``policy`` strategy's ``onnx`` file is made absolute (a relative path is to the YAML
file) and must exist; its ``policy`` callable ('package.module:attribute') must import.
A mistake is a :class:`~mresim_phys.errors.ScenarioError` naming the file and the field.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from mresim_phys.errors import ScenarioError
from mresim_phys.scenario.schema import PluginSpec, Scenario
from mresim_phys.strategies.policy.loaders import PolicyLoadError, load_callable


def policies_under(scenario: Scenario, folder: Path, source: str) -> Scenario:
    """``scenario`` with every policy robot's ``onnx`` path absolute, each policy checked."""
    team = with_policy_under(scenario.team, folder, source, "team")
    robots = [
        with_policy_under(r, folder, source, f"robots[{i}]") for i, r in enumerate(scenario.robots)
    ]
    return scenario.model_copy(update={"team": team, "robots": robots})


def with_policy_under(robot: Any, folder: Path, source: str, where: str) -> Any:
    """A robot (or the team) whose strategy, if ``policy``, has its source checked."""
    spec: PluginSpec | None = getattr(robot, "strategy", None)
    if spec is None or spec.name != "policy":
        return robot
    params = dict(spec.params)
    field = f"{where}.strategy.params"
    if params.get("onnx") is not None:
        path = Path(str(params["onnx"]))
        path = path if path.is_absolute() else folder / path
        if not path.is_file():
            raise ScenarioError(f"{source}: {field}.onnx: no such file {path}")
        params["onnx"] = str(path.resolve())
    if params.get("policy") is not None:
        try:
            load_callable(str(params["policy"]))
        except PolicyLoadError as exc:
            raise ScenarioError(f"{source}: {field}.policy: {exc}") from None
    strategy = spec.model_copy(update={"params": params})
    return robot.model_copy(update={"strategy": strategy})
