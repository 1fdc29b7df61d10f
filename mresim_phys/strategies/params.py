"""Strategy parameters (phase 0, input): every built-in strategy's ``Params`` model.

Pydantic and the standard library only, so validating a scenario never imports a strategy's
implementation (numba, pymunk, OpenCV): :mod:`mresim_phys.strategies.catalog` enters each
built-in with its model here and its class by reference. A strategy of your own may keep its
``Params`` beside its class (docs/writing-a-strategy.md).
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from mresim_phys.plugin import PluginParams


class StrategyParams(PluginParams):
    """Base for strategy parameters: unknown keys are errors."""

    replan_interval: int = 15


class FrontierParams(StrategyParams):
    """Parameters of greedy frontier exploration (defaults: the original's constants)."""

    replan_interval: int = Field(15, ge=1, description="Steps between replans.")
    min_frontier_size: int = Field(3, ge=1, description="Smallest frontier cluster (cells).")
    max_frontiers: int = Field(6, ge=1, description="Best frontiers entered in the auction.")
    teammate_memory: int = Field(500, ge=0, description="Steps a teammate's report stays valid.")
    horizon: float = Field(
        1.0,
        gt=0,
        description=(
            "First search horizon, in sensor ranges; doubles until no frontier beyond it"
            " could enter the best max_frontiers."
        ),
    )
    init_cycles: int = Field(
        3,
        ge=0,
        description=(
            "First steps taken as random-walk steps (the original's INIT_CYCLES), from the"
            " robot's seeded stream; none when the scenario sets vary_with_seed: false."
        ),
    )
    done_fraction: float | None = Field(
        0.95,
        gt=0,
        le=1,
        description=(
            "Mission complete (return to the base) once the robot's own map holds this"
            " fraction of the team's explorable area (docs/explorable.md), as the original's"
            " TERRITORY_PERCENT_EXPLORED_GOAL; null: only when no frontier is left."
        ),
    )
    done_after: int = Field(
        100, ge=0, description="Steps before the done_fraction rule may fire (the original: 100)."
    )
    replan_on_contact: bool = Field(
        True,
        description=(
            "Replan on the step after a contact when the frontier the robot chases has"
            " left its map (the original replans every step while in contact)."
        ),
    )
    give_up_radius: float = Field(
        10.0,
        gt=0,
        description=(
            "On reaching a frontier that is still there after facing it, its cells within"
            " this distance (cells) count a try: set aside until no untried frontier is"
            " left, then tried from another spot, given up after two tries (giveup.py)."
        ),
    )
    candidate_power: int = Field(
        2,
        ge=1,
        le=4,
        description=(
            "Which frontiers enter the auction: the max_frontiers best by size / d^power"
            " (d: path length). 4: by the auction's own utility; 1: as the original orders"
            " its frontiers (area / distance); 2 (the default) between. The smaller, the"
            " more far large frontiers enter and the more robots spread over a building's"
            " wings (docs/strategies.md)."
        ),
    )
    frontier_size: Literal["region", "cells"] = Field(
        "region",
        description=(
            "A frontier's size in its utility: 'region', the seen-but-unvisited region it"
            " borders (free cells outside safe space, as the original's frontier polygons;"
            " knowledge/frontier_regions.py), or 'cells', its own cells."
        ),
    )
    reach: float | None = Field(
        None,
        gt=0,
        description=(
            "How far (cells) a target may be from its frontier; default: max(clearance + 1,"
            " 1.41 (clearance + 0.5)), knowledge.targets.target_reach."
        ),
    )


class HungarianParams(FrontierParams):
    """Frontier exploration's parameters; ``max_frontiers`` bounds the assignment's columns."""

    max_frontiers: int = Field(
        8, ge=1, description="Best frontiers (by this robot's utility) in the assignment."
    )


class MinPosParams(FrontierParams):
    """Frontier exploration's parameters; ``max_frontiers`` bounds the frontiers ranked."""

    max_frontiers: int = Field(
        20, ge=1, description="Best frontiers (by this robot's utility) it ranks itself on."
    )


class NearestFrontierParams(FrontierParams):
    """Frontier exploration's parameters, for the nearest frontier: a frontier's size is
    its own cells (its utility is not used) and no mission-complete rule."""

    frontier_size: Literal["region", "cells"] = Field(
        "cells", description="Unused by the nearest-frontier choice; 'cells' skips the region."
    )
    done_fraction: float | None = Field(
        None, gt=0, le=1, description="Unused: the robot explores until no frontier is left."
    )


class VoronoiParams(NearestFrontierParams):
    """Nearest-frontier parameters; ``teammate_memory`` says whose Voronoi cells count."""


class RangeConstrainedParams(FrontierParams):
    """Greedy frontier exploration's parameters and how far from the base it explores."""

    range: float | None = Field(
        None,
        gt=0,
        description="Cells from the base a frontier may be (null: twice its radio range, the"
        " disk model's reach to a base of the same range).",
    )


class PeriodicReturnParams(FrontierParams):
    """Greedy frontier exploration's parameters and how often a robot reports."""

    period: int = Field(
        100, ge=1, description="Steps out of contact with the base before it goes back."
    )


class PotentialFieldParams(FrontierParams):
    """Greedy frontier exploration's parameters and the teammates' repulsion."""

    max_frontiers: int = Field(12, ge=1, description="Frontiers the robot weighs.")
    repulsion: float | None = Field(
        None, gt=0, description="Cells within which a teammate repels (null: 1/4 laser range)."
    )
    repulsion_weight: float = Field(
        1.0, ge=0, le=100, description="A teammate's repulsion against the best frontier's pull."
    )


class RRTFrontierParams(FrontierParams):
    """Greedy frontier exploration's parameters and its trees' growth."""

    eta: float = Field(15.0, gt=0, le=1000, description="A tree's step (cells).")
    global_steps: int = Field(150, ge=1, le=100_000, description="Global tree draws a decision.")
    local_steps: int = Field(80, ge=0, le=100_000, description="Local tree draws a decision.")
    detect_radius: float = Field(
        10.0, gt=0, le=1000, description="Frontier cells this near a detected point count."
    )
    max_points: int = Field(500, ge=1, le=100_000, description="Detected points kept.")


class RoleBasedParams(FrontierParams):
    """Greedy frontier exploration's parameters and the rendezvous rules (original values)."""

    wait: int = Field(60, ge=0, description="Steps to wait at the point after the agreed time.")
    backup_wait: int = Field(
        60, ge=0, description="Relay: further steps it waits before it gives its explorer up."
    )
    check_interval: int = Field(
        2, ge=1, description="Steps between checks whether to head for the meeting."
    )
    rendezvous: Literal["basic", "improved", "multi_point"] = Field(
        "basic",
        description=(
            "Meeting points: 'basic' (the frontier target, else where the explorer stands),"
            " 'improved' (the best skeleton junction near the frontier, as the original's"
            " useImprovedRendezvous) or 'multi_point' (the improved point for the explorer"
            " and, for the relay, the point linked with it through walls that is nearest the"
            " base's range, with a backup meeting where they agreed: the original's"
            " RVThroughWalls, SSRR 2014)."
        ),
    )


class RoleSwitchParams(RoleBasedParams):
    """Role-based parameters and the dynamic hierarchy's (the original's values)."""

    switch_interval: int = Field(10, ge=1, description="Steps between role switch checks.")
    min_between: int = Field(
        4, ge=0, description="Steps a robot waits after a switch before it switches again."
    )


class UtilityReturnParams(FrontierParams):
    """Greedy frontier exploration's parameters and the return rule's."""

    target_ratio: float = Field(
        0.9,
        gt=0,
        le=1,
        description=(
            "Go home when B / (B + N) falls below this (the original's TARGET_INFO_RATIO:"
            " 0.9 by default, 0.7 in its shipped configuration)."
        ),
    )
    handover_margin: float = Field(
        3.0,
        ge=0,
        description=(
            "Cells: of two robots that meet, the one farther from the base by more than"
            " this hands its undelivered cells to the other."
        ),
    )


class SectorParams(FrontierParams):
    """Frontier exploration's parameters and the sector meetings'."""

    meet_interval: int = Field(100, ge=1, description="Steps from an agreement to the meeting.")
    wait: int = Field(30, ge=0, description="Steps to wait at the meeting after its time.")
    check_interval: int = Field(
        2, ge=1, description="Steps between checks whether to head for a meeting."
    )
    first_bearing_deg: float = Field(
        0.0, description="Bearing from the base (degrees, x axis, y down) where sector 0 starts."
    )
    span_deg: float = Field(
        360.0,
        gt=0,
        le=360,
        description=(
            "The turn (degrees, from first_bearing_deg) the sectors share: less than 360 when"
            " the base stands at an edge of the open space."
        ),
    )


class RandomWalkParams(StrategyParams):
    """How far a random walk leg may go."""

    replan_interval: int = Field(15, ge=1, description="Steps between new random goals.")
    distance: float = Field(30.0, gt=0, description="Longest path (cells) to a random goal.")


class LeaderFollowerParams(FrontierParams):
    """Greedy frontier exploration's parameters for the leader, and the chain's."""

    replan_interval: int = Field(1, ge=1, description="Steps between decisions (the chain: 1).")
    frontier_interval: int = Field(
        10, ge=1, description="Steps between the leader's frontier searches (the original: 10)."
    )


class PolicyParams(StrategyParams):
    """A trained policy's source and what it sees and does (docs/learning.md)."""

    replan_interval: int = Field(
        15, ge=1, description="Steps between decisions when nothing else makes one due."
    )
    policy: str | None = Field(
        None,
        description=(
            "'package.module:attribute' of a callable taking the observation (a dict of"
            " numpy arrays) and returning the action."
        ),
    )
    onnx: str | None = Field(
        None,
        description=(
            "An ONNX file (onnxruntime, the 'learn' extra; a relative path is to the scenario"
            " file) whose inputs are named after observation keys; its first output is the"
            " action, or one score per slot."
        ),
    )
    external: bool = Field(
        False,
        description=(
            "Decisions come from a learning environment (mresim_phys.learn), which sets it;"
            " a scenario gives policy or onnx instead."
        ),
    )
    action: Literal["choice", "goal_cell", "velocity"] = Field(
        "choice",
        description=(
            "What an action is: a slot of the candidate table (continue, frontiers, meetings,"
            " the base), a goal point (fractions of the map's width and height) or a heading"
            " and speed fraction, asked every step the robot acts."
        ),
    )
    frontiers: int = Field(6, ge=1, le=32, description="Frontier slots of the candidate table.")
    meet: int = Field(2, ge=0, le=8, description="Meeting slots (nearest known teammates).")
    crop: int = Field(32, ge=8, le=256, description="Side (cells) of the egocentric crop.")
    coarse: int = Field(32, ge=4, le=256, description="Side of the coarse whole-map view.")
    coarse_stride: int = Field(
        2, ge=1, le=16, description="The coarse view samples every this-many rows and columns."
    )
    teammates: int = Field(8, ge=0, le=256, description="Rows of the teammate table.")
    age_scale: float = Field(
        100.0, gt=0, description="Steps that scale ages (a report this old reads 1)."
    )
    give_up_radius: float = Field(
        10.0,
        gt=0,
        description=(
            "A frontier reached and faced in vain: its cells within this distance (cells)"
            " count a try, as frontier's give_up_radius (strategies/giveup.py)."
        ),
    )

    @model_validator(mode="after")
    def _one_source(self) -> PolicyParams:
        """Exactly one of policy, onnx and external."""
        given = [k for k in ("policy", "onnx") if getattr(self, k) is not None]
        if self.external:
            given.append("external")
        if len(given) != 1:
            shown = " and ".join(given) if given else "none of them"
            raise ValueError(
                "the policy strategy takes its decisions from exactly one of policy"
                f" ('package.module:attribute'), onnx (a file) and external; got {shown}"
            )
        return self
