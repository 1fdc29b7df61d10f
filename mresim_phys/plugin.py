"""Plugins (shared by every phase): the base every plugin family's classes build on.

A plugin is a class with a registry ``name`` (the key used in YAML), a pydantic
``Params`` model of its parameters (validated when the scenario is loaded) and a
constructor taking one validated ``Params`` instance. Strategies, planners, comm
models and events are plugin families; each family adds its own methods through
a ``typing.Protocol`` and keeps its classes in a :class:`~mresim_phys.registry.Registry`.
"""

from __future__ import annotations

from typing import ClassVar

from pydantic import BaseModel

from mresim_phys.strict import Strict


class PluginParams(Strict):
    """Base for every plugin's parameters: unknown keys are errors, values are immutable,
    numbers finite, bounded and never booleans (:mod:`mresim_phys.strict`)."""


class Plugin:
    """A named, parametrised building block; ``name`` is its registry key."""

    name: ClassVar[str]
    Params: ClassVar[type[BaseModel]] = PluginParams

    def __init__(self, params: BaseModel) -> None:
        self.params = params
