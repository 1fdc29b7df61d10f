"""Exploration strategies (phase 4): a plugin family keyed by the YAML name.

Built-ins register themselves on import. Third-party strategies register through
the ``mresim_phys.strategies`` entry-point group, or are named in a scenario as
``package.module:ClassName``. See docs/writing-a-strategy.md.
"""

from __future__ import annotations

from mresim_phys.strategies import (
    assignment,
    frontier,
    leader_follower,
    random_walk,
    role_based,
    role_switch,
    sector,
    utility_return,
)
from mresim_phys.strategies.base import (
    STRATEGIES,
    Decision,
    RobotView,
    Strategy,
    StrategyParams,
    plan_context,
)

BUILT_IN = (
    "frontier",
    "random_walk",
    "hungarian",
    "min_pos",
    "utility_return",
    "leader_follower",
    "role_based",
    "role_switch",
    "sector_rendezvous",
)
assert {
    frontier.FrontierExploration.name,
    random_walk.RandomWalk.name,
    assignment.HungarianExploration.name,
    assignment.MinPosExploration.name,
    utility_return.UtilityReturn.name,
    leader_follower.LeaderFollower.name,
    role_based.RoleBased.name,
    role_switch.RoleSwitch.name,
    sector.SectorRendezvous.name,
} == set(BUILT_IN)

__all__ = [
    "BUILT_IN",
    "STRATEGIES",
    "Decision",
    "RobotView",
    "Strategy",
    "StrategyParams",
    "plan_context",
]
