"""The planner registry (phase 0, input): built-in names, their parameters, lazy classes.

Importing this module imports no planner: each built-in is entered with its ``Params`` model
(:mod:`mresim_phys.planning.params`) and a ``module:Class`` reference to its class, imported
when a robot's planner is first built. Third-party planners register through the
``mresim_phys.planners`` entry-point group or are named as ``package.module:ClassName``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from pydantic import BaseModel

from mresim_phys.planning import params as p
from mresim_phys.plugin import Family
from mresim_phys.registry import Registry

if TYPE_CHECKING:
    from mresim_phys.planning.base import Planner

PLANNERS: Registry[Planner] = Registry(
    "planner", "mresim_phys.planners", Family("mresim_phys.planning.base:Planner", p.PlannerParams)
)
BUILT_IN: dict[str, tuple[str, type[BaseModel]]] = {
    "astar": ("astar:AStar", p.PlannerParams),
    "jps": ("jps:JumpPointSearch", p.PlannerParams),
    "topological": ("topological:TopologicalPlanner", p.TopologicalParams),
}
PLANNERS.enter("mresim_phys.planning.", BUILT_IN)
