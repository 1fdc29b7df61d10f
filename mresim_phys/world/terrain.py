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

from mresim_phys.world.element_params import TerrainSpec
from mresim_phys.world.footprints import read_grey, regions_cells

TerrainGrid = NDArray[np.float32]


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
    regions = spec.regions or []
    for i, cells in regions_cells(regions, shape, "terrain.regions"):
        grid[cells] = np.float32(regions[i].factor)
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
