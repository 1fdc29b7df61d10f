"""The team's hierarchy (phase 0, input): parents, roles, and what the strategies need of them.

Checked by the scenario schema (``Scenario``) once its robots are known: parents name the
base or a robot of the team without cycles, a relay has a child, and the strategies that
work in pairs or chains (``role_based``, ``role_switch``, ``leader_follower``) find them.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol


class Named(Protocol):
    """Anything with a name (a strategy spec)."""

    @property
    def name(self) -> str: ...


class TeamMember(Protocol):
    """What the check reads of a robot's spec."""

    @property
    def name(self) -> str: ...

    @property
    def parent(self) -> str | None: ...

    @property
    def role(self) -> str: ...

    @property
    def strategy(self) -> Named: ...


def check_hierarchy(robots: Sequence[TeamMember]) -> None:
    """Parents name the base or another robot of the team, without cycles; a relay has a
    child (a relay nobody relays for has nothing to carry)."""
    names = {r.name for r in robots}
    parents = {r.name: r.parent for r in robots}
    for robot in robots:
        if robot.parent is not None and robot.parent not in names | {"base"}:
            raise ValueError(
                f"robots: {robot.name}'s parent {robot.parent!r} is neither 'base' nor a robot"
                f" of the team ({', '.join(sorted(names))})"
            )
        seen, at = [robot.name], robot.parent
        while at is not None and at != "base":
            if at in seen:
                chain = " -> ".join([*seen, at])
                raise ValueError(
                    f"robots: the parents form a cycle ({chain}); end chains at 'base'"
                )
            seen.append(at)
            at = parents[at]
    pairs_needed = "explorer / relay pairs"
    needs = {"role_based": pairs_needed, "role_switch": pairs_needed}
    needs["leader_follower"] = "a hierarchy"
    for strategy, what in needs.items():
        users = [r.name for r in robots if r.strategy.name == strategy]
        pairs = any(r.role == "relay" for r in robots) if what == pairs_needed else True
        if users and (not pairs or all(r.parent is None for r in robots)):
            raise ValueError(
                f"robots: {', '.join(users)} use{'s' if len(users) == 1 else ''} the strategy"
                f" {strategy}, which needs {what}: give each relay 'role: relay' and"
                " 'parent: base', and each explorer 'parent: <its relay>'"
            )
    children = {r.parent for r in robots}
    lonely = [r.name for r in robots if r.role == "relay" and r.name not in children]
    if lonely and any(r.parent is not None for r in robots):
        raise ValueError(
            f"robots: {', '.join(lonely)} {'is a relay' if len(lonely) == 1 else 'are relays'}"
            " but no robot names it as its parent; give a robot 'parent: NAME' or make it an"
            " explorer"
        )
