"""Scenario loading (phase 0, input edge): YAML file -> validated :class:`Scenario`.

Reads the file, validates it against the schema, resolves relative map paths
against the YAML file's folder and validates every plugin's parameters against
that plugin's own ``Params`` model, so ``mresim validate`` catches an unknown
strategy or a misspelt strategy parameter before anything runs. Every failure is
a :class:`ScenarioError` naming the file, the field path and what was expected.
"""

from __future__ import annotations

import difflib
from pathlib import Path
from typing import Any, TypeVar, get_args

from pydantic import BaseModel, ValidationError

from .comms import COMM_MODELS
from .errors import ScenarioError, UnknownPluginError
from .io import read_yaml_mapping
from .planners import PLANNERS
from .registry import Registry
from .scenario import PluginSpec, RobotParams, Scenario
from .strategies import STRATEGIES

RobotT = TypeVar("RobotT", bound=RobotParams)


def load_scenario(path: str | Path, **overrides: Any) -> Scenario:
    """Read, validate and resolve the scenario at ``path``; ``overrides`` replace top keys."""
    source = Path(path)
    data = read_yaml_mapping(source)
    for key, value in overrides.items():
        if isinstance(value, dict) and isinstance(data.get(key), dict):
            data[key] = {**data[key], **value}
        elif value is not None:
            data[key] = value
    scenario = validate_scenario(data, str(source))
    return resolve_map_path(scenario, source.resolve().parent)


def validate_scenario(data: dict[str, Any], source: str = "<scenario>") -> Scenario:
    """Schema-validate ``data`` and each plugin's params; errors name ``source``."""
    try:
        scenario = Scenario.model_validate(data)
    except ValidationError as exc:
        raise ScenarioError(describe_errors(source, exc)) from None
    check_event_robots(scenario, source)
    team = resolve_robot_plugins(scenario.team, source, "team")
    robots = [
        resolve_robot_plugins(r, source, f"robots[{i}]") for i, r in enumerate(scenario.robots)
    ]
    comm = scenario.communication
    params = resolve_params(COMM_MODELS, comm.model, comm.params, source, "communication.model")
    comm = comm.model_copy(update={"params": params})
    return scenario.model_copy(update={"robots": robots, "team": team, "communication": comm})


def check_event_robots(scenario: Scenario, source: str) -> None:
    """Every event must name a robot of the team."""
    names = [r.name for r in scenario.robots]
    for i, event in enumerate(scenario.events):
        if event.fail not in names:
            close = difflib.get_close_matches(event.fail, names, n=1)
            hint = f" Did you mean {close[0]!r}?" if close else ""
            raise ScenarioError(
                f"{source}: events[{i}].fail: no robot is called {event.fail!r}.{hint}"
                f" The robots are {names}."
            )


ROBOT_PLUGINS: dict[str, Registry[Any]] = {"strategy": STRATEGIES, "planner": PLANNERS}


def resolve_robot_plugins(robot: RobotT, source: str, where: str) -> RobotT:
    """A robot (or the team) with each plugin spec's params validated and filled in."""
    update = {
        key: resolve_plugin(registry, getattr(robot, key), source, f"{where}.{key}")
        for key, registry in ROBOT_PLUGINS.items()
    }
    return robot.model_copy(update=update)


def resolve_plugin(
    registry: Registry[Any], spec: PluginSpec, source: str, where: str
) -> PluginSpec:
    """A plugin spec with its params validated and every default filled in."""
    params = resolve_params(registry, spec.name, spec.params, source, f"{where}.name")
    return spec.model_copy(update={"params": params})


def resolve_params(
    registry: Registry[Any], name: str, params: dict[str, Any], source: str, where: str
) -> dict[str, Any]:
    """``params`` validated (defaults filled) by the ``Params`` model of plugin ``name``."""
    try:
        cls = registry.get(name)
    except UnknownPluginError as exc:
        raise ScenarioError(f"{source}: {where}: {exc}") from None
    params_model = getattr(cls, "Params", None)
    if not (isinstance(params_model, type) and issubclass(params_model, BaseModel)):
        raise ScenarioError(
            f"{source}: {where}: {name!r} is not a usable {registry.kind}: its class needs a"
            " 'Params' attribute that is a pydantic model of its parameters (subclass"
            " StrategyParams, PlannerParams or CommParams); see docs/writing-a-strategy.md."
        )
    prefix = where.rsplit(".", 1)[0] + ".params"
    try:
        return params_model.model_validate(params).model_dump()
    except ValidationError as exc:
        raise ScenarioError(
            describe_errors(source, exc, prefix=prefix, keys=list(params_model.model_fields))
        ) from None


def resolve_map_path(scenario: Scenario, folder: Path) -> Scenario:
    """The scenario with its map path made absolute (relative paths are to the YAML file)."""
    kind, value = scenario.map.source
    absolute = str((folder / Path(value).expanduser()).resolve())
    return scenario.model_copy(update={"map": scenario.map.model_copy(update={kind: absolute})})


def describe_errors(
    source: str, exc: ValidationError, prefix: str = "", keys: list[str] | None = None
) -> str:
    """One readable line per problem: ``file: field.path: what was wrong (got value)``.

    ``keys`` are the valid keys for 'did you mean' hints when the errors come from
    one flat model (a plugin's params); otherwise hints come from the schema model
    at the error's location.
    """
    lines = [
        describe_error(error, prefix, keys)
        for error in exc.errors(include_url=False)
        if not inherited_from_team(error, exc)
    ]
    count = len(lines)
    head = f"{source}: {count} problem{'s' if count > 1 else ''} in the scenario:"
    return "\n".join([head, *(f"  - {line}" for line in lines)])


def describe_error(error: Any, prefix: str, keys: list[str] | None = None) -> str:
    """One validation error as ``field.path: message``, with a hint for unknown keys."""
    path = field_path((*([prefix] if prefix else []), *error["loc"]))
    if error["type"] == "extra_forbidden":
        key = str(error["loc"][-1])
        valid = keys if keys is not None else keys_at(Scenario, error["loc"][:-1])
        close = difflib.get_close_matches(key, valid, n=1)
        hint = f"; did you mean {close[0]!r}?" if close else "; remove it or check the spelling"
        return f"{path}: unknown key {key!r}{hint}"
    message = str(error["msg"]).removeprefix("Value error, ")
    value = error.get("input")
    shown = error["type"] != "missing" and not isinstance(value, (dict, list))
    return f"{path}: {message}" + (f" (got {value!r})" if shown else "")


def field_path(loc: tuple[Any, ...]) -> str:
    """``('robots', 1, 'speed')`` -> ``robots[1].speed``."""
    text = ""
    for part in loc:
        if isinstance(part, int):
            text += f"[{part}]"
        elif part not in ("function-before[_from_name(), PluginSpec]",):
            text += f".{part}" if text else str(part)
    return text or "<top level>"


def inherited_from_team(error: Any, exc: ValidationError) -> bool:
    """A robot error that only repeats a ``team`` error (same field, same inherited value)."""
    loc = error["loc"]
    if len(loc) < 3 or loc[0] != "robots":
        return False
    return any(
        e["loc"] == ("team", *loc[2:]) and e.get("input") == error.get("input")
        for e in exc.errors(include_url=False)
    )


def keys_at(model: type[BaseModel], loc: tuple[Any, ...]) -> list[str]:
    """The keys the schema model found by walking ``loc`` from ``model`` accepts."""
    current: type[BaseModel] = model
    for part in loc:
        if isinstance(part, int):
            continue
        field = current.model_fields.get(str(part))
        nested = field and next(
            (
                t
                for t in (field.annotation, *get_args(field.annotation))
                if isinstance(t, type) and issubclass(t, BaseModel)
            ),
            None,
        )
        if nested is None:
            return []
        current = nested
    return list(current.model_fields)
