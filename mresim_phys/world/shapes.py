"""World (phase 0, events): the shapes of things that change the world, as whole cells.

The truth is a grid (``world/changes.py``), so every shape a scenario gives, a moving
obstacle's body or the region of a collapse, becomes the set of cells whose centre
lies inside it (at least the cell holding its anchor point, so nothing is too small
to exist). Shapes of moving obstacles are relative to the obstacle's centre:

* ``{circle: r}``: a disc of radius ``r`` cells;
* ``{box: [width, height]}``: an axis-aligned box;
* ``{polygon: [[x, y], ...]}``: a polygon, vertices relative to the centre.

Regions of collapses and debris are absolute: ``{box: [x0, y0, x1, y1]}`` (cells
``x0..x1-1`` by ``y0..y1-1``), ``{circle: [x, y, r]}``, ``{polygon: [[x, y], ...]}``
or ``{mask: file.png}`` (an image the size of the map; dark pixels are the region).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any

import cv2
import numpy as np
from pydantic import Discriminator, Field, Tag, field_validator
from skimage.measure import points_in_poly

from mresim_phys.strict import Strict
from mresim_phys.types import BoolGrid

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


def inside_polygon(vertices: np.ndarray, xs: np.ndarray, ys: np.ndarray) -> BoolGrid:
    """Which points (xs, ys) lie inside the polygon (points on its edge may go either way)."""
    points = np.column_stack((xs.ravel(), ys.ravel()))
    inside: BoolGrid = points_in_poly(points, vertices).reshape(xs.shape)  # type: ignore[no-untyped-call]
    return inside


def body_cells(shape: BodyShape) -> tuple[BoolGrid, tuple[int, int]]:
    """The footprint of ``shape`` centred on a cell's centre, and that cell's (row, col)
    inside the footprint. The footprint always holds its centre cell."""
    if isinstance(shape, CircleShape):
        reach = shape.circle
    elif isinstance(shape, BoxShape):
        reach = max(shape.box) / 2
    else:
        reach = float(np.abs(np.asarray(shape.polygon)).max())
    half = math.ceil(reach) + 1
    offsets = np.arange(-half, half + 1, dtype=float)
    dy, dx = np.meshgrid(offsets, offsets, indexing="ij")  # centre-to-centre offsets
    if isinstance(shape, CircleShape):
        cells = dx**2 + dy**2 <= shape.circle**2
    elif isinstance(shape, BoxShape):
        width, height = shape.box
        # centres in [-w/2, w/2) x [-h/2, h/2): a box w cells wide covers w cells
        cells = (-width / 2 <= dx) & (dx < width / 2) & (-height / 2 <= dy) & (dy < height / 2)
    else:
        cells = inside_polygon(np.asarray(shape.polygon, dtype=float), dx, dy)
    cells[half, half] = True
    rows, cols = np.flatnonzero(cells.any(axis=1)), np.flatnonzero(cells.any(axis=0))
    trimmed = cells[rows[0] : rows[-1] + 1, cols[0] : cols[-1] + 1]
    return np.ascontiguousarray(trimmed), (half - int(rows[0]), half - int(cols[0]))


def region_cells(region: Region, shape: tuple[int, int], base: Path | None = None) -> BoolGrid:
    """The map's cells (a mask of ``shape``) that ``region`` covers; ``base`` resolves a
    relative mask path. ValueError if the region covers no cell of the map."""
    rows, cols = shape
    out = np.zeros(shape, dtype=bool)
    if isinstance(region, BoxRegion):
        x0, y0, x1, y1 = region.box
        out[min(y0, rows) : min(y1, rows), min(x0, cols) : min(x1, cols)] = True
    elif isinstance(region, MaskRegion):
        out = read_mask(region.mask if base is None else base / region.mask, shape)
    else:
        ys, xs = np.mgrid[0:rows, 0:cols].astype(float) + 0.5
        if isinstance(region, CircleRegion):
            x, y, r = region.circle
            out = (xs - x) ** 2 + (ys - y) ** 2 <= r * r
        else:
            out = inside_polygon(np.asarray(region.polygon, dtype=float), xs, ys)
    if not out.any():
        raise ValueError(f"the region {region.model_dump(mode='json')} covers no cell of the map")
    return out


def read_grey(path: Path, shape: tuple[int, int], what: str) -> np.ndarray:
    """The greyscale image at ``path`` (``what`` names it in errors), which must be the
    map's size."""
    image = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
    if image is None:
        raise ValueError(f"cannot read the {what} {path}")
    if image.shape != shape:
        raise ValueError(
            f"the {what} {path} is {image.shape[1]}x{image.shape[0]} pixels; the map is"
            f" {shape[1]}x{shape[0]}: give one the size of the map"
        )
    return image


def read_mask(path: Path, shape: tuple[int, int]) -> BoolGrid:
    """The dark pixels (< 128) of the image at ``path``, which must be the map's size."""
    mask: BoolGrid = read_grey(path, shape, "mask image") < 128
    return mask
