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

from mresim_phys.columns import COLUMNS, DEFAULTS
from mresim_phys.comms import COMM_MODELS
from mresim_phys.errors import MapError, ScenarioError, UnknownPluginError
from mresim_phys.knowledge.teammates import BASE_NAME
from mresim_phys.planning import PLANNERS
from mresim_phys.registry import Registry
from mresim_phys.render.layers import parse_layers
from mresim_phys.scenario.faults import paired_problem
from mresim_phys.scenario.maps import MapSpec
from mresim_phys.scenario.overrides import apply_overrides
from mresim_phys.scenario.policies import policies_under
from mresim_phys.scenario.radio_files import resolve_radio
from mresim_phys.scenario.readers import read_yaml_mapping
from mresim_phys.scenario.schema import (
    CommSpec,
    PluginSpec,
    RobotParams,
    Scenario,
)
from mresim_phys.scenario.units import to_cells
from mresim_phys.strategies import STRATEGIES
from mresim_phys.world.element_params import absolute_layer
from mresim_phys.world.event_catalog import EVENTS
from mresim_phys.world.shapes import region_under

RobotT = TypeVar("RobotT", bound=RobotParams)


def load_scenario(path: str | Path, **overrides: Any) -> Scenario:
    """Read, validate and resolve the scenario at ``path`` with ``overrides`` applied.

    Overrides merge deeply (see :mod:`mresim_phys.scenario.overrides`): ``team=`` changes
    every robot, ``robots={"B": {...}}`` one robot, ``**{"team.sensor.range": 80}`` one field.
    """
    source = Path(path)
    own = read_yaml_mapping(source)
    folder = source.resolve().parent
    overriding = any(value is not None for value in overrides.values())
    if overriding:  # otherwise the validation below is of the file's own values
        check_own_values(own_in_cells(own, str(source), folder), str(source))
    data = apply_overrides(own, overrides, str(source))
    scenario = validate_scenario(data, str(source), folder)
    if not overriding:
        check_event_steps(scenario, str(source))
    scenario = resolve_map_path(scenario, folder, str(source))
    scenario = resolve_radio(scenario, folder, str(source))
    return resolve_mask_paths(scenario, folder, str(source))


def own_in_cells(own: dict[str, Any], source: str, folder: Path) -> dict[str, Any]:
    """The file's own values in cells, for :func:`check_own_values`; as they are when they
    cannot be converted alone (an override gives the ``dt`` that metres need)."""
    try:
        return to_cells(own, source, folder)
    except ScenarioError:
        return {k: v for k, v in own.items() if k != "units"}


def check_own_values(data: dict[str, Any], source: str) -> None:
    """The file's own values, before any override: an override (``--steps 10``) replaces a
    value, it does not excuse a wrong one (``steps: -5``). Keys the file leaves out are not
    problems here (an override or a default may give them); an event the file schedules
    after its own step cap would never happen, and is refused.
    """
    try:
        scenario = Scenario.model_validate(data)
    except ValidationError as exc:
        own = [
            describe_error(error, "")
            for error in exc.errors(include_url=False)
            if error["type"] != "missing" and not inherited_from_team(error, exc)
        ]
        if own:
            raise ScenarioError(problems_text(source, own)) from None
        return
    check_event_steps(scenario, source)


def check_event_steps(scenario: Scenario, source: str) -> None:
    """An event after the scenario's step cap would never happen: refused."""
    late = [(i, e.step) for i, e in enumerate(scenario.events) if e.step > scenario.steps]
    if late:
        where = ", ".join(f"events[{i}] (step {step})" for i, step in late)
        raise ScenarioError(
            f"{source}: {where} come{'s' if len(late) == 1 else ''} after the step cap"
            f" (steps: {scenario.steps}) and would never happen; give event steps from 0 to"
            f" {scenario.steps}, or raise 'steps'."
        )


def validate_scenario(
    data: dict[str, Any], source: str = "<scenario>", folder: Path | None = None
) -> Scenario:
    """Schema-validate ``data`` and each plugin's params; errors name ``source``. A scenario
    in metres (``units: m``) is turned into cells first, its map read from ``folder``
    (default the working folder) when its path is relative (``scenario/units.py``)."""
    data = to_cells(data, source, folder if folder is not None else Path.cwd())
    try:
        scenario = Scenario.model_validate(data)
    except ValidationError as exc:
        raise ScenarioError(describe_errors(source, exc)) from None
    check_event_robots(scenario, source)
    check_layers(scenario, source)
    check_columns(scenario, source)
    problem = paired_problem(scenario)
    if problem is not None:
        raise ScenarioError(f"{source}: {problem}")
    team = resolve_robot_plugins(scenario.team, source, "team")
    robots = [
        resolve_robot_plugins(r, source, f"robots[{i}]") for i, r in enumerate(scenario.robots)
    ]
    comm = resolve_comm(scenario.communication, source)
    return scenario.model_copy(update={"robots": robots, "team": team, "communication": comm})


def check_event_robots(scenario: Scenario, source: str) -> None:
    """Every agent an event names must be in the team (some events may also name the base)."""
    names = [r.name for r in scenario.robots]
    for i, event in enumerate(scenario.events):
        for where, name, base_allowed in event.agent_names():
            known = [BASE_NAME, *names] if base_allowed else names
            check_agent_name(name, known, source, f"events[{i}].{where}")


def check_columns(scenario: Scenario, source: str) -> None:
    """Every column ``metrics.columns`` names must be a metric column, not a default one,
    named once."""
    seen: set[str] = set()
    for i, name in enumerate(scenario.metrics.columns):
        where = f"{source}: metrics.columns[{i}]"
        try:
            cls = COLUMNS.get(name)
        except UnknownPluginError as exc:
            raise ScenarioError(f"{where}: {exc}") from None
        if cls.name in DEFAULTS:
            raise ScenarioError(
                f"{where}: {name!r} is a default column of metrics.csv, always written;"
                " list only optional columns here (docs/metric-columns.md)."
            )
        if cls.name in seen:
            raise ScenarioError(
                f"{where}: {name!r} is column {cls.name!r}, named twice; name each column once."
            )
        seen.add(cls.name)


def check_layers(scenario: Scenario, source: str) -> None:
    """``render.layers`` must parse, and name only robots of the team (as a run checks)."""
    try:
        parse_layers(scenario.render.layers).check_agents([r.name for r in scenario.robots])
    except ValueError as exc:
        raise ScenarioError(f"{source}: render.layers: {exc}") from None


def check_agent_name(name: str, names: list[str], source: str, where: str) -> None:
    """``name`` must be one of ``names``; the error suggests the closest."""
    if name not in names:
        close = difflib.get_close_matches(name, names, n=1)
        hint = f" Did you mean {close[0]!r}?" if close else ""
        raise ScenarioError(
            f"{source}: {where}: no robot is called {name!r}.{hint} The robots are {names}."
        )


def resolve_comm(comm: CommSpec, source: str) -> CommSpec:
    """The communication spec with the main and control models' params validated."""
    params = resolve_params(COMM_MODELS, comm.model, comm.params, source, "communication.model")
    control = comm.control
    if control is not None:
        where = "communication.control.model"
        control_params = resolve_params(COMM_MODELS, control.model, control.params, source, where)
        control = control.model_copy(update={"params": control_params})
    return comm.model_copy(update={"params": params, "control": control})


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
        params_model = registry.params_model(name)
    except UnknownPluginError as exc:
        raise ScenarioError(f"{source}: {where}: {exc}") from None
    if params_model is None:
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


def resolve_map_path(scenario: Scenario, folder: Path, source: str = "<scenario>") -> Scenario:
    """The scenario with its map paths (``map``, and ``prior.map`` if given) made absolute
    (relative paths are to the YAML file).

    The files must exist (their content is read when the run is built); a missing file or
    a path the system cannot use is a :class:`MapError` naming ``source`` and the field.
    """
    prior = scenario.prior
    if prior is not None:
        prior = prior.model_copy(
            update={"map": absolute_map(prior.map, folder, source, "prior.map")}
        )
    return scenario.model_copy(
        update={"map": absolute_map(scenario.map, folder, source, "map"), "prior": prior}
    )


def absolute_map(spec: MapSpec, folder: Path, source: str, field: str) -> MapSpec:
    """``spec`` with its file's path made absolute; a MapError naming ``field`` if the
    file is missing."""
    kind, value = spec.source
    try:
        path = (folder / Path(value).expanduser()).resolve()
        problem = None if path.is_file() else "is not a file" if path.exists() else "does not exist"
    except (OSError, ValueError) as exc:  # a NUL byte, a name too long for the system
        path, problem = Path(value), f"is not a usable path ({exc})"
    if problem is not None:
        raise MapError(
            f"{source}: {field}.{kind}: {clip(str(path), 300)} {problem}. Check the path and its"
            " spelling; a relative path is relative to the scenario file's folder."
        )
    return spec.model_copy(update={kind: str(path)})


def resolve_mask_paths(scenario: Scenario, folder: Path, source: str = "<scenario>") -> Scenario:
    """The scenario with the mask images of collapse events, random debris, terrain and
    ground classes, and the policy robots' ONNX files, made absolute (relative paths are to
    the YAML file), so the run can be built anywhere; a missing policy file or callable is
    a ScenarioError naming ``source`` (``scenario/policies.py``)."""
    scenario = policies_under(scenario, folder, source)
    events = [e.under(folder) for e in scenario.events]
    debris = scenario.random_debris
    if debris is not None:
        debris = debris.model_copy(update={"region": region_under(debris.region, folder)})
    terrain = absolute_layer(scenario.terrain, folder)
    ground = absolute_layer(scenario.ground, folder)
    faults = scenario.faults
    if faults is not None:
        hazards = [
            h.model_copy(update={"region": region_under(h.region, folder)}) for h in faults.hazards
        ]
        faults = faults.model_copy(update={"hazards": hazards})
    return scenario.model_copy(
        update={
            "events": events,
            "random_debris": debris,
            "terrain": terrain,
            "ground": ground,
            "faults": faults,
        }
    )


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
    return problems_text(source, lines)


def problems_text(source: str, lines: list[str]) -> str:
    """``source: N problems in the scenario:`` and one indented line per problem."""
    count = len(lines)
    head = f"{source}: {count} problem{'s' if count > 1 else ''} in the scenario:"
    return "\n".join([head, *(f"  - {line}" for line in lines)])


def describe_error(error: Any, prefix: str, keys: list[str] | None = None) -> str:
    """One validation error as ``field.path: message``, with a hint for unknown keys."""
    loc, event_model = untagged(tuple(error["loc"]))
    path = field_path((*([prefix] if prefix else []), *loc))
    if error["type"] == "extra_forbidden":
        key = str(loc[-1])
        if keys is None and event_model is not None:
            keys = list(event_model.model_fields)
        valid = keys if keys is not None else keys_at(Scenario, loc[:-1])
        close = difflib.get_close_matches(key, valid, n=1)
        hint = f"; did you mean {close[0]!r}?" if close else "; remove it or check the spelling"
        return f"{path}: unknown key {key!r}{hint}"
    message = str(error["msg"]).removeprefix("Value error, ")
    if not loc and not prefix and error["type"] == "value_error":
        return message  # a whole-scenario rule: its message names the fields
    value = error.get("input")
    shown = error["type"] != "missing" and not isinstance(value, (dict, list))
    return f"{path}: {message}" + (f" (got {shown_value(value)})" if shown else "")


def shown_value(value: Any, width: int = 60) -> str:
    """``repr(value)``, cut to ``width`` characters so a message stays one paragraph."""
    return clip(repr(value), width)


def clip(text: str, width: int) -> str:
    """``text`` cut to ``width`` characters, ending in '...' when cut.

    >>> clip("abcdefgh", 6)
    'abc...'
    """
    return text if len(text) <= width else text[: width - 3] + "..."


def untagged(loc: tuple[Any, ...]) -> tuple[tuple[Any, ...], type[BaseModel] | None]:
    """``loc`` without the event-kind tag pydantic inserts, and the event model it names.

    >>> untagged(("events", 0, "blackout", "until"))[0]
    ('events', 0, 'until')
    """
    if len(loc) > 2 and loc[0] == "events" and loc[2] in EVENTS.names():
        return (*loc[:2], *loc[3:]), EVENTS.params_model(str(loc[2]))
    return loc, None


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
