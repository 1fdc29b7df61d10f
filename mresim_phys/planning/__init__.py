"""Path planners (phase 4b): a plugin family keyed by the YAML name.

``team: {planner: astar | jps | topological}`` (or per robot) picks how a robot finds
the path it follows to the goal its strategy chose. Importing the package is light:
:data:`PLANNERS` (``catalog``) holds every built-in by name, with its ``Params`` model
(``params``) and a reference to its class, imported when a robot's planner is built.
Third-party planners register through the ``mresim_phys.planners`` entry-point group or are
named as ``package.module:ClassName``. See docs/planning.md.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

from mresim_phys.planning.catalog import BUILT_IN, PLANNERS
from mresim_phys.planning.params import PlannerParams

if TYPE_CHECKING:
    from mresim_phys.planning.base import Planner
    from mresim_phys.planning.topocache import shared_map
    from mresim_phys.planning.topomap import TopologicalMap

INTERFACE = {  # name -> the module it comes from, on first use
    "Planner": "base",
    "shared_map": "topocache",
    "TopologicalMap": "topomap",
}


def __getattr__(name: str) -> object:
    """The planner interface's names, imported when first asked for."""
    if name in INTERFACE:
        return getattr(importlib.import_module(f"{__name__}.{INTERFACE[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["BUILT_IN", "PLANNERS", "Planner", "PlannerParams", "TopologicalMap", "shared_map"]
