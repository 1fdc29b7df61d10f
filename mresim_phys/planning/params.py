"""Planner parameters (phase 0, input): every built-in planner's ``Params`` model.

Pydantic and the standard library only: :mod:`mresim_phys.planning.catalog` enters each
built-in planner with its model here and its class by reference, so validating a scenario
imports no planner (numba, OpenCV).
"""

from __future__ import annotations

from pydantic import Field

from mresim_phys.plugin import PluginParams


class PlannerParams(PluginParams):
    """Base for planner parameters: unknown keys are errors."""

    smooth: bool = Field(
        False,
        description="Shorten the grid path by line-of-sight shortcuts through passable cells.",
    )


class TopologicalParams(PlannerParams):
    """Parameters of the topological planner."""

    node_spacing: int = Field(
        10, ge=2, le=200, description="Skeleton node spacing: one node per block of this size."
    )
    rebuild_fraction: float = Field(
        0.05,
        ge=0,
        le=1,
        description="Rebuild when this fraction of the built map's passable cells changed.",
    )
    corridor: int = Field(
        1,
        ge=0,
        le=5,
        description="Rings of neighbouring regions searched besides the route's (0 = none).",
    )
