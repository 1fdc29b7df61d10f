"""World (phase 0, input to motion and sensing): variable terrain, a speed factor per cell.

A scenario's ``terrain:`` key gives the ground truth of how fast a robot can drive on
each cell, as a factor in (0, 1] of its ``speed`` (1 = open floor, 0.3 = mud):

* ``{image: mud.png, min_factor: 0.1}``: a greyscale image the size of the map; a pixel
  of value ``v`` (0..255) gives ``factor = max(min_factor, v / 255)``, so white is open
  floor and black the slowest ground ``min_factor`` allows (colour images are read as
  their luminance);
* ``{regions: [{box: [x0, y0, x1, y1], factor: 0.3}, {circle: [x, y, r], factor: 0.5},
  {polygon: [[x, y], ...], factor: 0.2}, {mask: file.png, factor: 0.4}]}``: the region
  shapes of :mod:`mresim_phys.world.shapes`; every other cell is 1, and where regions
  overlap the later one wins.

The grid is float32, C-contiguous, and never changes during a run. A scenario without
``terrain`` has no grid at all (``None``): every consumer keeps its uniform-cost path.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, model_validator

from mresim_phys.strict import Strict
from mresim_phys.world.shapes import (
    BoxRegion,
    CircleRegion,
    MaskRegion,
    PolygonRegion,
    Region,
    read_grey,
    region_cells,
)

TerrainGrid = NDArray[np.float32]
SHAPE_KEYS = ("box", "circle", "polygon", "mask")


class TerrainRegion(Strict):
    """One region of slower ground: one of ``box``, ``circle``, ``polygon``, ``mask``."""

    box: tuple[int, int, int, int] | None = Field(None, description="[x0, y0, x1, y1] in cells.")
    circle: tuple[float, float, float] | None = Field(None, description="[x, y, r] in cells.")
    polygon: list[tuple[float, float]] | None = Field(
        None, min_length=3, description="Vertices [[x, y], ...] in cells."
    )
    mask: Path | None = Field(None, description="PNG the size of the map; dark pixels are in.")
    factor: float = Field(gt=0, le=1, description="Speed factor on the region, in (0, 1].")

    @model_validator(mode="after")
    def _one_shape(self) -> TerrainRegion:
        given = [k for k in SHAPE_KEYS if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError(
                "a terrain region needs exactly one of 'box', 'circle', 'polygon' or 'mask'"
                f" (got {given or 'none'})"
            )
        self.region()  # the shape's own checks (a box's corners in order, r > 0)
        return self

    def region(self) -> Region:
        """The shape as a region model of :mod:`mresim_phys.world.shapes`."""
        if self.box is not None:
            return BoxRegion(box=self.box)
        if self.circle is not None:
            return CircleRegion(circle=self.circle)
        if self.polygon is not None:
            return PolygonRegion(polygon=self.polygon)
        assert self.mask is not None
        return MaskRegion(mask=self.mask)


class TerrainSpec(Strict):
    """Variable terrain: a greyscale ``image`` or a list of ``regions`` (exactly one)."""

    image: Path | None = Field(
        None,
        description="Greyscale image the size of the map: factor = max(min_factor, value/255).",
    )
    min_factor: float = Field(
        0.1, gt=0, le=1, description="Image terrain: the slowest factor (black pixels)."
    )
    regions: list[TerrainRegion] | None = Field(
        None, description="Regions with a speed factor each; other cells are 1 (later wins)."
    )

    @model_validator(mode="after")
    def _one_source(self) -> TerrainSpec:
        if (self.image is None) == (self.regions is None):
            raise ValueError("give exactly one of 'image: file.png' or 'regions: [...]'")
        return self


def absolute_terrain(spec: TerrainSpec | None, folder: Path) -> TerrainSpec | None:
    """``spec`` with its image and mask paths made absolute (relative to ``folder``)."""
    if spec is None:
        return None
    image = spec.image and (folder / spec.image.expanduser()).resolve()
    regions = spec.regions and [
        r.model_copy(update={"mask": r.mask and (folder / r.mask.expanduser()).resolve()})
        for r in spec.regions
    ]
    return spec.model_copy(update={"image": image, "regions": regions})


def terrain_grid(spec: TerrainSpec | None, shape: tuple[int, int]) -> TerrainGrid | None:
    """The truth factor grid of ``spec`` on a map of ``shape`` (None without terrain).

    Raises:
        ValueError: naming the field (``terrain.image``, ``terrain.regions[i]``) when the
            image cannot be read, is not the map's size, or a region covers no cell.
    """
    if spec is None:
        return None
    if spec.image is not None:
        return image_factors(spec.image, shape, spec.min_factor)
    grid = np.ones(shape, dtype=np.float32)
    for i, region in enumerate(spec.regions or []):
        try:
            cells = region_cells(region.region(), shape)
        except ValueError as exc:
            raise ValueError(f"terrain.regions[{i}]: {exc}") from None
        grid[cells] = np.float32(region.factor)
    return grid


def image_factors(path: Path, shape: tuple[int, int], min_factor: float) -> TerrainGrid:
    """``max(min_factor, value / 255)`` per pixel of the greyscale image at ``path``."""
    try:
        image = read_grey(path, shape, "terrain image")
    except ValueError as exc:
        raise ValueError(f"terrain.image: {exc}") from None
    factors = np.maximum(image.astype(np.float32) / np.float32(255.0), np.float32(min_factor))
    return np.ascontiguousarray(factors, dtype=np.float32)


def factor_at(grid: TerrainGrid | None, xy: tuple[float, float]) -> float:
    """The factor of the cell holding world point ``xy`` (1 without terrain or off the map)."""
    if grid is None:
        return 1.0
    row, col = int(np.floor(xy[1])), int(np.floor(xy[0]))
    rows, cols = grid.shape
    if 0 <= row < rows and 0 <= col < cols:
        return float(grid[row, col])
    return 1.0
