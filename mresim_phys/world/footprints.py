"""World (phase 0, events): shapes as whole cells of the truth grid.

Every shape a scenario gives (:mod:`mresim_phys.world.shapes`: a moving obstacle's body,
the region of a collapse, of debris or of terrain) becomes the set of cells whose centre
lies inside it, at least the cell holding its anchor point, so nothing is too small to
exist. Mask regions are images the size of the map (dark pixels are in).
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Protocol

import cv2
import numpy as np
from skimage.measure import points_in_poly

from mresim_phys.types import BoolGrid
from mresim_phys.world.shapes import (
    BodyShape,
    BoxRegion,
    BoxShape,
    CircleRegion,
    CircleShape,
    MaskRegion,
    Region,
)


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


class HasRegion(Protocol):
    """A scenario entry with a region shape (terrain and ground regions)."""

    def region(self) -> Region: ...


def regions_cells(
    entries: Sequence[HasRegion], shape: tuple[int, int], field: str
) -> Iterator[tuple[int, BoolGrid]]:
    """(index, cells) of each entry's region on a map of ``shape``, in order; a ValueError
    naming ``field[i]`` for a region that covers no cell of the map."""
    for i, entry in enumerate(entries):
        try:
            yield i, region_cells(entry.region(), shape)
        except ValueError as exc:
            raise ValueError(f"{field}[{i}]: {exc}") from None
