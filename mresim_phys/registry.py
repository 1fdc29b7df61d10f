"""Plugin registries (shared): a YAML name -> a class, for every plugin family.

A registry is filled at import time by a class decorator (the class's own
``name`` is its key), can be extended by a third-party package through an entry
point group, and resolves ``"package.module:ClassName"`` references for one-off
user classes. A built-in may also be entered *lazily* (:meth:`Registry.lazy`): its name,
the ``module:Class`` reference of its implementation and its ``Params`` model, the way
Gymnasium's ``EnvSpec.entry_point`` does. Validating a scenario then reads only the
parameter models (modules of pydantic and the standard library); the implementation, with
numba, pymunk or OpenCV behind it, is imported when the class itself is asked for.
:meth:`Registry.make` builds a plugin from its parameters. Unknown names raise
:class:`~mresim_phys.errors.UnknownPluginError` listing the close matches.

A registry given its :class:`~mresim_phys.plugin.Family` takes only classes of that
family: a ``module:Class`` reference or an entry point naming a class of another family
(a strategy given as a planner) is an :class:`UnknownPluginError` saying which family was
expected and, when it is one, which family the class belongs to. A ``module:Class``
reference imports that module, running its code: a file that names one is code.
"""

from __future__ import annotations

import difflib
import importlib
import weakref
from collections.abc import Mapping
from importlib.metadata import entry_points
from typing import Any, Generic, TypeVar

from pydantic import BaseModel

from mresim_phys.errors import UnknownPluginError
from mresim_phys.plugin import Family, named_object

T = TypeVar("T")
REGISTRIES: weakref.WeakSet[Registry[Any]] = weakref.WeakSet()  # to name a class's family


def with_article(noun: str) -> str:
    """``noun`` after 'a' or 'an'.

    >>> with_article("event"), with_article("planner")
    ('an event', 'a planner')
    """
    return f"{'an' if noun[:1] in 'aeiou' else 'a'} {noun}"


class Registry(Generic[T]):
    """Name -> plugin class, with entry-point discovery and ``module:Class`` references."""

    def __init__(self, kind: str, entry_point_group: str, family: Family | None = None) -> None:
        self.kind = kind
        self.entry_point_group = entry_point_group
        self.family = family  # None: any class is taken
        self._classes: dict[str, type[T]] = {}
        self._broken: dict[str, str] = {}  # entry points that failed to load: why
        self._discovered = False
        self._from_entry_points: set[str] = set()
        self._lazy: dict[str, tuple[str, type[BaseModel]]] = {}  # name -> (module:Class, Params)
        REGISTRIES.add(self)

    def lazy(self, name: str, reference: str, params: type[BaseModel]) -> None:
        """Enter built-in ``name``, implemented by the class ``reference`` names
        (``package.module:Class``, imported when first asked for) with parameters
        ``params``; the class, once imported, must register itself under ``name``."""
        if name in self._lazy or name in self._classes:
            raise ValueError(f"{self.kind} {name!r} is already registered")
        self._lazy[name] = (reference, params)

    def register(self, cls: type[T]) -> type[T]:
        """Class decorator adding ``cls`` under its ``name``; a duplicate name or a class of
        another family is an error."""
        name = getattr(cls, "name", None)
        if not isinstance(name, str) or not name:
            raise ValueError(f"a {self.kind} class needs a 'name' class attribute (its YAML key)")
        if name in self._classes and self._classes[name] is not cls:
            raise ValueError(f"{self.kind} {name!r} is already registered")
        problem = self.misfit(cls, name) or self._unlike_entry(cls, name)
        if problem:
            raise ValueError(problem)
        self._classes[name] = cls
        return cls

    def enter(self, prefix: str, entries: Mapping[str, tuple[str, type[BaseModel]]]) -> None:
        """:meth:`lazy` for each ``name: (reference, Params)`` of ``entries``, the reference
        read after ``prefix`` (``"mresim_phys.strategies."`` + ``"frontier:Frontier"``)."""
        for name, (reference, params) in entries.items():
            self.lazy(name, prefix + reference, params)

    def _unlike_entry(self, cls: type, name: str) -> str:
        """Why ``cls`` is not the class entered lazily as ``name`` ('' if it is, or if
        ``name`` was not entered lazily)."""
        if name not in self._lazy:
            return ""
        reference, params = self._lazy[name]
        if reference != f"{cls.__module__}:{cls.__qualname__}":
            return f"{self.kind} {name!r} is entered as {reference!r}, not {cls.__qualname__!r}"
        if getattr(cls, "Params", None) is not params:
            return f"{self.kind} {name!r} is entered with Params {params.__name__}"
        return ""

    def fits(self, cls: type) -> bool:
        """Whether ``cls`` belongs to this registry's family (a registry without one: no)."""
        return self.family is not None and not self.family.misfits(cls)

    def misfit(self, cls: type, shown: str) -> str:
        """Why ``cls`` (given as ``shown``) is not of this family, one paragraph ('' if it is)."""
        problems = self.family.misfits(cls) if self.family is not None else []
        if self.family is None or not problems:
            return ""
        other = next((r.kind for r in REGISTRIES if r is not self and r.fits(cls)), None)
        kind = with_article(self.kind)
        which = f"it is {with_article(other)}, not {kind}" if other else f"it is not {kind}"
        return (
            f"{self.kind} {shown!r} cannot be used: {which} ({'; '.join(problems)})."
            f" {kind.capitalize()} class has {self.family.rule()}; see"
            " docs/writing-a-strategy.md."
        )

    def params_model(self, name: str) -> type[BaseModel] | None:
        """The pydantic ``Params`` model of plugin ``name`` (None if it has none usable); a
        lazily entered built-in's without importing its implementation."""
        if name in self._lazy and name not in self._classes:
            return self._lazy[name][1]
        model = getattr(self.get(name), "Params", None)
        return model if isinstance(model, type) and issubclass(model, BaseModel) else None

    def make(self, name: str, params: Mapping[str, Any] | None = None) -> T:
        """A new instance of plugin ``name`` built from ``params`` (validated by its Params)."""
        cls: Any = self.get(name)
        return cls(cls.Params.model_validate(dict(params or {})))  # type: ignore[no-any-return]

    def registered(self) -> list[type[T]]:
        """The classes registered in this process (not those of entry points), in the order
        they were registered."""
        return [cls for name, cls in self._classes.items() if name not in self._from_entry_points]

    def names(self) -> list[str]:
        """All registered names (built-ins and discovered plugins), sorted."""
        self._discover()
        return sorted({*self._classes, *self._lazy})

    def get(self, name: str) -> type[T]:
        """The class for ``name``: a registered name or a ``package.module:Class`` path."""
        if ":" in name:
            return self._import(name)
        self._discover()
        if name in self._broken:
            raise UnknownPluginError(self._broken[name])
        if name in self._lazy and name not in self._classes:
            self._load(name)
        if name not in self._classes:
            raise UnknownPluginError(self._unknown_message(name))
        return self._classes[name]

    def _load(self, name: str) -> None:
        """Import the implementation of lazily entered ``name`` (which registers it)."""
        reference = self._lazy[name][0]
        cls = named_object(reference)  # first: importing it registers it
        if self._classes.get(name) is not cls:
            raise RuntimeError(f"{reference} did not register itself as {self.kind} {name!r}")

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
        problem = self.misfit(cls, reference)
        if problem:
            raise UnknownPluginError(problem)
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
            if ep.name in self._classes or ep.name in self._lazy:
                continue
            try:
                cls = ep.load()
            except Exception as exc:  # a broken third-party package must not stop the rest
                self._broken[ep.name] = (
                    f"{self.kind} {ep.name!r} (entry point {ep.value!r}) cannot be loaded:"
                    f" {type(exc).__name__}: {exc}. Reinstall or fix the package providing it."
                )
                continue
            problem = self._entry_point_problem(f"{ep.name} (entry point {ep.value})", cls)
            if problem:
                self._broken[ep.name] = problem
            else:
                self._classes[ep.name] = cls
                self._from_entry_points.add(ep.name)

    def _entry_point_problem(self, shown: str, loaded: Any) -> str:
        """Why what an entry point loaded is no class of this family ('' if it is one)."""
        if not isinstance(loaded, type):
            kind = type(loaded).__name__
            return f"{self.kind} {shown!r} cannot be used: it is a {kind}, not a class."
        return self.misfit(loaded, shown)
