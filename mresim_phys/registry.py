"""Plugin registries (shared): a YAML name -> a class, for every plugin family.

A registry is filled at import time by a class decorator (the class's own
``name`` is its key), can be extended by a third-party package through an entry
point group, and resolves ``"package.module:ClassName"`` references for one-off
user classes. :meth:`Registry.make` builds a plugin from its parameters. Unknown
names raise :class:`~mresim_phys.errors.UnknownPluginError` listing the close matches.
"""

from __future__ import annotations

import difflib
import importlib
from collections.abc import Mapping
from importlib.metadata import entry_points
from typing import Any, Generic, TypeVar

from pydantic import BaseModel

from mresim_phys.errors import UnknownPluginError

T = TypeVar("T")


class Registry(Generic[T]):
    """Name -> plugin class, with entry-point discovery and ``module:Class`` references."""

    def __init__(self, kind: str, entry_point_group: str) -> None:
        self.kind = kind
        self.entry_point_group = entry_point_group
        self._classes: dict[str, type[T]] = {}
        self._broken: dict[str, str] = {}  # entry points that failed to load: why
        self._discovered = False

    def register(self, cls: type[T]) -> type[T]:
        """Class decorator adding ``cls`` under its ``name``; a duplicate name is an error."""
        name = getattr(cls, "name", None)
        if not isinstance(name, str) or not name:
            raise ValueError(f"a {self.kind} class needs a 'name' class attribute (its YAML key)")
        if name in self._classes and self._classes[name] is not cls:
            raise ValueError(f"{self.kind} {name!r} is already registered")
        self._classes[name] = cls
        return cls

    def params_model(self, name: str) -> type[BaseModel] | None:
        """The pydantic ``Params`` model of plugin ``name`` (None if it has none usable)."""
        model = getattr(self.get(name), "Params", None)
        return model if isinstance(model, type) and issubclass(model, BaseModel) else None

    def make(self, name: str, params: Mapping[str, Any] | None = None) -> T:
        """A new instance of plugin ``name`` built from ``params`` (validated by its Params)."""
        cls: Any = self.get(name)
        return cls(cls.Params.model_validate(dict(params or {})))  # type: ignore[no-any-return]

    def names(self) -> list[str]:
        """All registered names (built-ins and discovered plugins), sorted."""
        self._discover()
        return sorted(self._classes)

    def get(self, name: str) -> type[T]:
        """The class for ``name``: a registered name or a ``package.module:Class`` path."""
        if ":" in name:
            return self._import(name)
        self._discover()
        if name in self._broken:
            raise UnknownPluginError(self._broken[name])
        if name not in self._classes:
            raise UnknownPluginError(self._unknown_message(name))
        return self._classes[name]

    def _unknown_message(self, name: str) -> str:
        close = difflib.get_close_matches(name, self.names(), n=3, cutoff=0.5)
        hint = f" Did you mean {' or '.join(repr(c) for c in close)}?" if close else ""
        return (
            f"unknown {self.kind} {name!r}.{hint} Known: {', '.join(self.names())}."
            f" A class of your own can be given as 'package.module:ClassName'."
        )

    def _import(self, reference: str) -> type[T]:
        """The class a ``package.module:Class`` reference names; any failure is an
        :class:`UnknownPluginError` saying what went wrong and how the reference reads."""
        module_name, _, attr = reference.partition(":")
        if not module_name.strip() or not attr.strip():
            raise UnknownPluginError(self._bad_reference(reference, "a part is empty"))
        try:
            module = importlib.import_module(module_name)
        except Exception as exc:  # ImportError, a relative name, or the module's own error
            raise UnknownPluginError(
                self._bad_reference(reference, f"cannot import {module_name!r}: {exc}")
                + " Check that the module is installed or on PYTHONPATH."
            ) from None
        cls = getattr(module, attr, None)
        if not isinstance(cls, type):
            found = "no" if cls is None else f"a {type(cls).__name__} but no"
            raise UnknownPluginError(
                self._bad_reference(reference, f"module {module_name!r} has {found} class {attr!r}")
            )
        return cls

    def _bad_reference(self, reference: str, problem: str) -> str:
        return (
            f"{self.kind} {reference!r} cannot be used: {problem}. A class of your own is"
            " given as 'package.module:ClassName'."
        )

    def _discover(self) -> None:
        """Add the classes of installed entry points; a broken one is named when asked for."""
        if self._discovered:
            return
        self._discovered = True
        for ep in entry_points(group=self.entry_point_group):
            if ep.name in self._classes:
                continue
            try:
                self._classes[ep.name] = ep.load()
            except Exception as exc:  # a broken third-party package must not stop the rest
                self._broken[ep.name] = (
                    f"{self.kind} {ep.name!r} (entry point {ep.value!r}) cannot be loaded:"
                    f" {type(exc).__name__}: {exc}. Reinstall or fix the package providing it."
                )
