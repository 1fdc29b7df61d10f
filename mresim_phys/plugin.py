"""Plugins (shared by every phase): the base every plugin family's classes build on.

A plugin is a class with a registry ``name`` (the key used in YAML), a pydantic
``Params`` model of its parameters (validated when the scenario is loaded) and a
constructor taking one validated ``Params`` instance. Strategies, planners, comm
models and events are plugin families; each family adds its own methods through
a ``typing.Protocol`` and keeps its classes in a :class:`~mresim_phys.registry.Registry`.
A :class:`Family` says what a class must have to belong to one: its ``Params`` subclass
the family's params base, and the family's methods; a class of another family given by
``package.module:Class`` is refused when it is resolved, not deep inside a run.
"""

from __future__ import annotations

import importlib
import inspect
from dataclasses import dataclass
from typing import Any, ClassVar

from pydantic import BaseModel

from mresim_phys.strict import Strict


def named_object(reference: str) -> Any:
    """The object a ``package.module:attribute`` reference names, its module imported now
    (the lazy entries of registries, features and commands; a user's reference goes through
    :meth:`~mresim_phys.registry.Registry.get`, which explains a bad one)."""
    module, _, attribute = reference.partition(":")
    return getattr(importlib.import_module(module), attribute)


class PluginParams(Strict):
    """Base for every plugin's parameters: unknown keys are errors, values are immutable,
    numbers finite, bounded and never booleans (:mod:`mresim_phys.strict`)."""


class Plugin:
    """A named, parametrised building block; ``name`` is its registry key."""

    name: ClassVar[str]
    Params: ClassVar[type[BaseModel]] = PluginParams

    def __init__(self, params: BaseModel) -> None:
        self.params = params


@dataclass(frozen=True)
class Family:
    """What a family's classes have: a ``Params`` subclassing ``params`` and the public
    methods of ``protocol`` (the family's ``typing.Protocol``, or its ``module:Class``
    reference, imported when a class is first checked: a registry of a light module can
    name the protocol of a heavy one)."""

    protocol: type | str
    params: type[BaseModel]

    @property
    def methods(self) -> list[str]:
        """The methods the protocol asks for (its properties are instance state)."""
        protocol = self.protocol
        if isinstance(protocol, str):
            protocol = named_object(protocol)
        members = vars(protocol).items()
        return [n for n, v in members if inspect.isfunction(v) and not n.startswith("_")]

    def misfits(self, cls: type) -> list[str]:
        """Why ``cls`` is not of this family ([] if it is)."""
        problems: list[str] = []
        params = getattr(cls, "Params", None)
        if not (isinstance(params, type) and issubclass(params, self.params)):
            shown = f"Params {params.__name__}" if isinstance(params, type) else "no Params"
            problems.append(f"it has {shown}, not a subclass of {self.params.__name__}")
        missing = [m for m in self.methods if not callable(getattr(cls, m, None))]
        if missing:
            problems.append(f"it has no {', '.join(f'{m}()' for m in missing)}")
        return problems

    def rule(self) -> str:
        """What a class of this family has, for messages."""
        methods = ", ".join(f"{m}()" for m in self.methods)
        plural = "s" if len(self.methods) > 1 else ""
        return f"a Params model subclassing {self.params.__name__} and the method{plural} {methods}"
