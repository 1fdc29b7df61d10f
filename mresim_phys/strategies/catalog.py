"""The strategy registry (phase 0, input): built-in names, their parameters, lazy classes.

Importing this module imports no strategy: each built-in is entered with its ``Params`` model
(:mod:`mresim_phys.strategies.params`) and a ``module:Class`` reference to its class, imported
when a run first asks for it. Third-party strategies register through the
``mresim_phys.strategies`` entry-point group, or are named as ``package.module:ClassName``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from pydantic import BaseModel

from mresim_phys.plugin import Family
from mresim_phys.registry import Registry
from mresim_phys.strategies import params as p

if TYPE_CHECKING:
    from mresim_phys.strategies.base import Strategy

STRATEGIES: Registry[Strategy] = Registry(
    "strategy",
    "mresim_phys.strategies",
    Family("mresim_phys.strategies.base:Strategy", p.StrategyParams),
)
BUILT_IN: dict[str, tuple[str, type[BaseModel]]] = {
    "frontier": ("frontier:FrontierExploration", p.FrontierParams),
    "random_walk": ("random_walk:RandomWalk", p.RandomWalkParams),
    "hungarian": ("assignment:HungarianExploration", p.HungarianParams),
    "min_pos": ("assignment:MinPosExploration", p.MinPosParams),
    "utility_return": ("utility_return:UtilityReturn", p.UtilityReturnParams),
    "leader_follower": ("leader_follower:LeaderFollower", p.LeaderFollowerParams),
    "role_based": ("role_based:RoleBased", p.RoleBasedParams),
    "role_switch": ("role_switch:RoleSwitch", p.RoleSwitchParams),
    "sector_rendezvous": ("sector:SectorRendezvous", p.SectorParams),
    "nearest_frontier": ("baselines:NearestFrontier", p.NearestFrontierParams),
    "voronoi": ("baselines:VoronoiExploration", p.VoronoiParams),
    "range_constrained": ("baselines:RangeConstrained", p.RangeConstrainedParams),
    "periodic_return": ("baselines:PeriodicReturn", p.PeriodicReturnParams),
    "potential_field": ("baselines:PotentialField", p.PotentialFieldParams),
    "rrt_frontier": ("rrt_frontier:RRTFrontier", p.RRTFrontierParams),
    "policy": ("policy.strategy:PolicyStrategy", p.PolicyParams),
}
STRATEGIES.enter("mresim_phys.strategies.", BUILT_IN)
