"""World (phase 0, input): the shapes of things that change the world, as validated models.

Pydantic and the standard library only (a scenario is validated without numpy or OpenCV);
``world/footprints.py`` turns a shape into the cells whose centre lies inside it. Shapes
of moving obstacles are relative to the obstacle's centre:

* ``{circle: r}``: a disc of radius ``r`` cells;
* ``{box: [width, height]}``: an axis-aligned box;
* ``{polygon: [[x, y], ...]}``: a polygon, vertices relative to the centre.

Regions of collapses and debris are absolute: ``{box: [x0, y0, x1, y1]}`` (cells
``x0..x1-1`` by ``y0..y1-1``), ``{circle: [x, y, r]}``, ``{polygon: [[x, y], ...]}``
or ``{mask: file.png}`` (an image the size of the map; dark pixels are the region).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

from pydantic import Discriminator, Field, Tag, field_validator

from mresim_phys.strict import Strict

Point = tuple[float, float]
Positive = Annotated[float, Field(gt=0, le=1000)]


class CircleShape(Strict):
    """A disc around the obstacle's centre."""

    circle: Positive = Field(description="Radius in cells.")


class BoxShape(Strict):
    """An axis-aligned box around the obstacle's centre."""

    box: tuple[Positive, Positive] = Field(description="[width, height] in cells.")


class PolygonShape(Strict):
    """A polygon; its vertices are relative to the obstacle's centre."""

    polygon: list[tuple[float, float]] = Field(
        min_length=3, description="Vertices [[x, y], ...] relative to the centre, in cells."
    )


def keyed(*keys: str) -> Discriminator:
    """A discriminator that picks a union member by which of ``keys`` the mapping has
    (the YAML key that names the kind), so a mistake is reported for that kind only."""

    def kind(value: Any) -> str | None:
        if isinstance(value, dict):
            return next((k for k in keys if k in value), None)
        return next((k for k in keys if hasattr(value, k)), None)

    wanted = " or ".join(f"'{k}'" for k in keys)
    return Discriminator(
        kind, custom_error_type="kind", custom_error_message=f"give one of the keys {wanted}"
    )


BodyShape = Annotated[
    Annotated[CircleShape, Tag("circle")]
    | Annotated[BoxShape, Tag("box")]
    | Annotated[PolygonShape, Tag("polygon")],
    keyed("circle", "box", "polygon"),
]


class BoxRegion(Strict):
    """Cells x0..x1-1 by y0..y1-1."""

    box: tuple[int, int, int, int] = Field(description="[x0, y0, x1, y1] in cells.")

    @field_validator("box")
    @classmethod
    def _ordered(cls, box: tuple[int, int, int, int]) -> tuple[int, int, int, int]:
        x0, y0, x1, y1 = box
        if not (0 <= x0 < x1 and 0 <= y0 < y1):
            raise ValueError(f"box {list(box)} must have 0 <= x0 < x1 and 0 <= y0 < y1")
        return box


class CircleRegion(Strict):
    """The cells whose centre lies within ``r`` of (x, y)."""

    circle: tuple[float, float, Positive] = Field(description="[x, y, r] in cells.")


class PolygonRegion(Strict):
    """The cells whose centre lies inside the polygon."""

    polygon: list[tuple[float, float]] = Field(
        min_length=3, description="Vertices [[x, y], ...] in cells."
    )


class MaskRegion(Strict):
    """The dark pixels of an image the size of the map."""

    mask: Path = Field(description="PNG the size of the map; pixels darker than 128 are in.")


def region_under(region: Region | None, folder: Path) -> Region | None:
    """``region`` with a mask image's path made absolute (relative to ``folder``)."""
    if not isinstance(region, MaskRegion):
        return region
    return region.model_copy(update={"mask": (folder / region.mask.expanduser()).resolve()})


Region = Annotated[
    Annotated[BoxRegion, Tag("box")]
    | Annotated[CircleRegion, Tag("circle")]
    | Annotated[PolygonRegion, Tag("polygon")]
    | Annotated[MaskRegion, Tag("mask")],
    keyed("box", "circle", "polygon", "mask"),
]
