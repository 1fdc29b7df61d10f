"""Scenario schema (phase 0, input): where maps come from, the truth's and a prior one.

:class:`MapSpec` names the ground truth's file (``map:``); :class:`PriorSpec`
(``prior:``) names a map some robots know before the mission, in the same format,
which may be out of date (the building plan before a collapse) and may be degraded
at stated rates (``knowledge/prior.py`` applies them from the run's ``prior`` stream).
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from mresim_phys.strict import Strict

MAX_MAP_CELLS = 40_000_000  # 6300 x 6300 cells; a world this size already needs GBs


class MapSpec(Strict):
    """Where the ground truth comes from: exactly one of ``image``, ``grid``, ``ros``."""

    image: str | None = Field(None, description="PNG/JPG/GIF/BMP floor plan; dark = obstacle.")
    grid: str | None = Field(None, description="Text grid in the original MRESim format.")
    ros: str | None = Field(None, description="ROS map_server YAML (with its PGM).")
    resolution: float | None = Field(
        None, gt=0, description="Metres per cell, only used to report metres."
    )
    threshold: float = Field(
        0.5, gt=0, le=1, description="Image maps: luminance below threshold*255 is obstacle."
    )
    negate: bool = Field(False, description="Image maps: bright = obstacle instead of dark.")
    max_cells: int = Field(
        MAX_MAP_CELLS,
        ge=1,
        le=10**9,
        description="The largest map read (width x height cells); a bigger one is refused"
        " before it is loaded.",
    )

    @model_validator(mode="after")
    def _one_source(self) -> MapSpec:
        given = [k for k in ("image", "grid", "ros") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError(
                "give exactly one map source: 'image: file.png', 'grid: file.txt' or"
                f" 'ros: map.yaml' (got {given or 'none'})"
            )
        return self

    @property
    def source(self) -> tuple[str, str]:
        """(kind, path) of the one map source."""
        for kind in ("image", "grid", "ros"):
            value = getattr(self, kind)
            if value is not None:
                return kind, value
        raise AssertionError("validated MapSpec has a source")


class PriorSpec(Strict):
    """A map robots start with: their belief before the mission (not observations)."""

    map: MapSpec = Field(description="The prior map, in the format of 'map' and of its size.")
    robots: list[str] | Literal["all"] = Field(
        "all", description="Robots that start with it: a list of names, or 'all'."
    )
    drop: float = Field(
        0.0, ge=0, le=1, description="Share of cells the prior does not hold (left unknown)."
    )
    flip: float = Field(
        0.0, ge=0, le=1, description="Share of the cells it holds given wrong (free <-> wall)."
    )
