"""Scenario overrides (phase 0, input): change a scenario's YAML data before it is validated.

The rules, used by ``Simulation.from_yaml(path, **overrides)``, ``load_scenario``
and sweeps:

* a mapping merges into a mapping key by key, at any depth; anything else (a
  number, a string, a list) replaces what was there; ``None`` leaves it as is;
  a mapping never replaces a number, boolean or list the file gave where a
  mapping belongs (``render: 5`` stays, and validation reports it);
* ``team`` changes the defaults AND every robot: a team override beats a field a
  robot set for itself (``team={"speed": 5}`` makes every robot's speed 5);
* ``robots`` may be a mapping from robot name to that robot's changes
  (``robots={"B": {"sensor": {"range": 80}}}``); a list replaces the whole team;
* a dotted key names a nested field: ``{"team.sensor.range": 80}`` equals
  ``{"team": {"sensor": {"range": 80}}}``.
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from typing import Any

from mresim_phys.errors import ScenarioError


def deep_merge(base: Any, change: Any) -> Any:
    """``change`` merged into ``base`` (mappings key by key, anything else replaces).

    >>> deep_merge({"a": {"b": 1, "c": 2}}, {"a": {"c": 3}})
    {'a': {'b': 1, 'c': 3}}
    """
    if change is None or (isinstance(change, Mapping) and malformed_section(base)):
        return base
    if isinstance(base, Mapping) and isinstance(change, Mapping):
        merged = dict(base)
        for key, value in change.items():
            if value is not None:  # None leaves the key as it is, absent included
                merged[key] = deep_merge(base.get(key), value)
        return merged
    return copy.deepcopy(change)


def malformed_section(value: Any) -> bool:
    """A value no mapping should be merged over: a number, boolean or list where the
    override expects a section (a string may be a shorthand such as ``strategy: frontier``)."""
    return isinstance(value, (int, float, list))


def expand_dotted(overrides: Mapping[str, Any]) -> dict[str, Any]:
    """Dotted keys turned into nested mappings.

    >>> expand_dotted({"team.sensor.range": 80, "seed": 2})
    {'team': {'sensor': {'range': 80}}, 'seed': 2}
    """
    nested: dict[str, Any] = {}
    for key, value in overrides.items():
        *parents, leaf = key.split(".")
        change: Any = {leaf: value}
        for parent in reversed(parents):
            change = {parent: change}
        nested = deep_merge(nested, change)
    return nested


def merge_robots(robots: Any, change: Any, source: str) -> Any:
    """Apply ``robots`` changes: a mapping by robot name merges, a list replaces."""
    if not isinstance(change, Mapping) or not isinstance(robots, list):
        return deep_merge(robots, change)
    names = [r.get("name") for r in robots if isinstance(r, Mapping)]
    unknown = sorted(set(change) - set(names))
    if unknown:
        raise ScenarioError(
            f"{source}: overrides name robots {unknown} that the scenario does not have;"
            f" its robots are {names}."
        )
    return [
        deep_merge(r, change.get(r.get("name"))) if isinstance(r, Mapping) else r for r in robots
    ]


def apply_overrides(
    data: Mapping[str, Any], overrides: Mapping[str, Any], source: str = "<scenario>"
) -> dict[str, Any]:
    """The scenario data with ``overrides`` applied by the rules in this module's docstring."""
    result = dict(data)
    for key, change in expand_dotted(overrides).items():
        if change is None:  # leaves the key as it is: a missing key keeps its default
            continue
        if key == "robots":
            result[key] = merge_robots(result.get(key), change, source)
            continue
        result[key] = deep_merge(result.get(key), change)
        if key == "team" and isinstance(change, Mapping) and isinstance(result.get("robots"), list):
            result["robots"] = [
                deep_merge(r, change) if isinstance(r, Mapping) else r for r in result["robots"]
            ]
    return result
