"""Sweep axes (sweeps, input): one axis value written into a scenario's YAML data.

The rules (``docs/sweeps.md``):

* a dotted path names a field (``team.comm_range``); missing sections are created, and
  ``team.*`` changes every robot too (the overrides' rules, ``scenario/overrides.py``);
* ``robots.<name>.<field>`` changes one robot;
* a path through a list (``faults.random.mtbf``) changes every entry of the list (a missing
  list gets one entry);
* ``null`` switches the thing off: the entries of a list the path goes through are dropped
  (``faults.random.mtbf: null`` = no random failures), a plain field is set to null;
* ``robots.count`` sets the team size (``sweeps/placement.py``).

A path that runs into a number, a string or a boolean where it needs a section is an
error naming the path; unknown field names are caught by the schema when the arm is
checked (with a close match).
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from typing import Any, get_args, get_origin

from pydantic import BaseModel

from mresim_phys.scenario.overrides import apply_overrides
from mresim_phys.scenario.schema import Scenario
from mresim_phys.sweeps.study import StudyError

COUNT = "robots.count"


def apply_axis(data: dict[str, Any], path: str, value: Any, source: str) -> dict[str, Any]:
    """``data`` (scenario YAML data) with the field at ``path`` set to ``value``."""
    parts = path.split(".")
    if any(not p for p in parts):
        raise StudyError(f"{source}: axis {path!r} is not a dotted path such as team.comm_range.")
    list_at = first_list(data, parts, path, source)
    if list_at is not None:
        return set_in_list(data, parts, list_at, value, source)
    if value is None:
        return set_null(data, parts, path, source)
    return apply_overrides(data, {path: value}, source)


def first_list(data: Mapping[str, Any], parts: list[str], path: str, source: str) -> int | None:
    """The index in ``parts`` of the first field that holds a list (robots excepted), or
    None; StudyError if the path runs into a value that is no section."""
    node: Any = data
    for k, part in enumerate(parts[:-1]):
        node = node.get(part) if isinstance(node, Mapping) else None
        if node is None:
            return schema_list(parts)
        if isinstance(node, list) and not (k == 0 and part == "robots"):
            return k
        if isinstance(node, list):
            return None  # robots by name: the overrides' rules
        if isinstance(node, (bool, int, float)):
            raise not_a_section(path, parts, k, node, source)
    return None


def not_a_section(path: str, parts: list[str], k: int, node: Any, source: str) -> StudyError:
    """The error of a path running into ``node`` (no section) at ``parts[k]``."""
    where = ".".join(parts[: k + 1])
    return StudyError(
        f"{source}: axis {path!r}: {where} is {node!r}, not a section, so it has no"
        f" field {parts[k + 1]!r}. Check the path against docs/scenario-reference.md."
    )


def schema_list(parts: list[str]) -> int | None:
    """The index in ``parts`` of the first field the scenario schema declares a list
    (robots excepted), or None."""
    model: type[BaseModel] = Scenario
    for k, part in enumerate(parts[:-1]):
        field = model.model_fields.get(part)
        if field is None:
            return None
        kinds = [field.annotation, *get_args(field.annotation)]
        if any(get_origin(t) is list for t in kinds):
            return None if k == 0 and part == "robots" else k
        nested = [t for t in kinds if isinstance(t, type) and issubclass(t, BaseModel)]
        if not nested:
            return None
        model = nested[0]
    return None


def set_in_list(
    data: dict[str, Any], parts: list[str], at: int, value: Any, source: str
) -> dict[str, Any]:
    """Set ``parts[at + 1:]`` in every entry of the list at ``parts[: at + 1]`` (``value``
    None: drop the entries)."""
    result = copy.deepcopy(data)
    parent: dict[str, Any] = result
    for part in parts[:at]:
        if not isinstance(parent.get(part), dict):
            parent[part] = {}
        parent = parent[part]
    key, rest = parts[at], ".".join(parts[at + 1 :])
    entries = parent.get(key) or []
    if value is None:
        parent[key] = []
        return result
    if not entries:
        entries = [{}]
    parent[key] = [
        apply_axis(e, rest, value, source) if isinstance(e, dict) else e for e in entries
    ]
    return result


def set_null(data: dict[str, Any], parts: list[str], path: str, source: str) -> dict[str, Any]:
    """``data`` with the field at ``parts`` set to null (and, for a team field, the robots'
    own values of it removed, as a team override beats them; ``robots.<name>.<field>``: that
    robot's field)."""
    result = copy.deepcopy(data)
    node, start = result, 0
    if parts[0] == "robots" and len(parts) > 2 and isinstance(result.get("robots"), list):
        node, start = robot_named(result["robots"], parts[1], path, source), 2
    for k in range(start, len(parts) - 1):
        child = node.get(parts[k])
        if child is None:
            child = node[parts[k]] = {}
        if not isinstance(child, dict):
            raise not_a_section(path, parts, k, child, source)
        node = child
    node[parts[-1]] = None
    if parts[0] == "team" and isinstance(result.get("robots"), list):
        for robot in result["robots"]:
            drop_path(robot, parts[1:])
    return result


def robot_named(robots: list[Any], name: str, path: str, source: str) -> dict[str, Any]:
    """The robot called ``name``; StudyError naming the team if there is none."""
    found = [r for r in robots if isinstance(r, dict) and r.get("name") == name]
    if not found:
        names = [r.get("name") for r in robots if isinstance(r, dict)]
        raise StudyError(
            f"{source}: axis {path!r} names robot {name!r}, which the scenario does not have;"
            f" its robots are {names}."
        )
    return found[0]


def drop_path(node: Any, parts: list[str]) -> None:
    """Remove the field at ``parts`` from ``node`` if it is there."""
    for part in parts[:-1]:
        node = node.get(part) if isinstance(node, dict) else None
    if isinstance(node, dict):
        node.pop(parts[-1], None)


def shown(values: Mapping[str, Any]) -> str:
    """Axis values as ``path=value, ...`` for messages and labels.

    >>> shown({"team.strategy": "frontier", "robots.count": 4})
    'team.strategy=frontier, robots.count=4'
    """
    return ", ".join(f"{k}={'null' if v is None else v}" for k, v in values.items())
