"""Path planners (phase 4b): a plugin family keyed by the YAML name.

``team: {planner: astar | jps | topological}`` (or per robot) picks how a robot finds
the path it follows to the goal its strategy chose. Built-ins register themselves on
import; third-party planners register through the ``mresim_phys.planners`` entry-point
group or are named as ``package.module:ClassName``. See docs/planning.md.
"""

from __future__ import annotations

from mresim_phys.planning import astar, jps, topological
from mresim_phys.planning.base import PLANNERS, Planner, PlannerParams
from mresim_phys.planning.topocache import shared_map
from mresim_phys.planning.topomap import TopologicalMap

BUILT_IN = ("astar", "jps", "topological")
assert {astar.AStar.name, jps.JumpPointSearch.name, topological.TopologicalPlanner.name} == set(
    BUILT_IN
)

__all__ = ["BUILT_IN", "PLANNERS", "Planner", "PlannerParams", "TopologicalMap", "shared_map"]
