"""Exploration strategies (phase 4): a plugin family keyed by the YAML name.

Importing the package is light: :data:`STRATEGIES` (``catalog``) holds every built-in by
name, with its ``Params`` model (``params``) and a reference to its class, imported when a
run asks for it. Third-party strategies register through the ``mresim_phys.strategies``
entry-point group, or are named in a scenario as ``package.module:ClassName``. The
strategy interface (``Strategy``, ``RobotView``, ``Decision``, ``plan_context``) comes from
``base`` when first used. See docs/writing-a-strategy.md.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

from mresim_phys.strategies.catalog import BUILT_IN, STRATEGIES
from mresim_phys.strategies.params import StrategyParams

if TYPE_CHECKING:
    from mresim_phys.strategies.base import Decision, RobotView, Strategy, plan_context

INTERFACE = ("Decision", "RobotView", "Strategy", "plan_context")  # from base, on first use


def __getattr__(name: str) -> object:
    """The strategy interface's names, imported from ``base`` when first asked for."""
    if name in INTERFACE:
        return getattr(importlib.import_module("mresim_phys.strategies.base"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "BUILT_IN",
    "STRATEGIES",
    "Decision",
    "RobotView",
    "Strategy",
    "StrategyParams",
    "plan_context",
]
