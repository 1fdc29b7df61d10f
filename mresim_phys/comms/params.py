"""Comm-model parameters (phase 0, input): every built-in comm model's ``Params`` model.

Pydantic and the standard library only: :mod:`mresim_phys.comms.catalog` enters each
built-in comm model with its model here and its class by reference, so validating a
scenario imports no comm model (numba, pymunk).
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from mresim_phys.plugin import PluginParams


class CommParams(PluginParams):
    """Base for comm-model parameters: unknown keys are errors."""


class DiskParams(CommParams):
    """The disk model has no parameters: ranges come from each agent."""


class LineOfSightParams(CommParams):
    """How thick the sight line is."""

    clearance: float = Field(
        0.0, ge=0, description="Radius (cells) of the sight line; the original used 0.5 px."
    )


class PathLossParams(CommParams):
    """The original's PropModel1 constants by default."""

    reference_dbm: float = Field(
        -93.0, description="Signal (dBm) at the reference distance, i.e. at the agent's comm_range."
    )
    exponent: float = Field(
        2.5,
        ge=1.0,
        le=10.0,
        description="Path-loss exponent n (2 in free space, 1.6-6 indoors).",
    )
    wall_db: float = Field(3.65, ge=0, description="Attenuation per wall crossed (WAF, dB).")
    max_walls: float = Field(125, ge=0, description="Cap C on the walls (or wall cells) counted.")
    cutoff_dbm: float = Field(-93.0, description="Weakest signal (dBm) that still links.")
    walls: Literal["count", "thickness"] = Field(
        "count", description="count: separate walls crossed; thickness: cells of wall crossed."
    )
    cell_db: float = Field(
        1.0, ge=0, description="thickness mode: attenuation per cell of wall crossed (dB)."
    )
