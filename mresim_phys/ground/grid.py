"""Ground classes (phase 0, world): the true class of every cell, and each robot's access.

The scenario's ``ground:`` block (``ground/spec.py``) becomes a uint8 grid the map's size:
0 is plain floor, ``i + 1`` the class ``names[i]``. An image gives a cell the class whose
legend colour its pixel has exactly (any other colour: floor); regions are drawn over it in
order, the later winning. The grid never changes during a run.

A robot's :class:`Access` is what it can cross: its speed factor per class (its
``crosses``, else the class's default), and from it, on the truth, the cells it cannot
enter (``barred``) and the cost multipliers of the cells it crosses slowly (``slowness``,
None when it crosses every class at full speed).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from mresim_phys.ground.spec import GroundSpec
from mresim_phys.snapshot import GroundLayer
from mresim_phys.types import BoolGrid, FloatArray
from mresim_phys.world.footprints import regions_cells

ClassGrid = NDArray[np.uint8]


@dataclass(frozen=True)
class Ground:
    """The true ground classes of the map: the grid and the class names (``names[i]`` is
    class ``i + 1``), with each class's default factor and legend colour (RGB)."""

    grid: ClassGrid
    names: tuple[str, ...]
    defaults: tuple[float, ...]
    colours: tuple[tuple[int, int, int], ...]

    def factors(self, crosses: dict[str, float] | None) -> FloatArray:
        """A robot's speed factor per class value (index 0: floor, 1)."""
        own = crosses or {}
        values = [
            own.get(name, default) for name, default in zip(self.names, self.defaults, strict=True)
        ]
        return np.array([1.0, *values], dtype=np.float64)

    @classmethod
    def from_meta(cls, meta: dict[str, Any], grid: ClassGrid) -> Ground:
        """The classes a run log holds (:meth:`meta`, the grid from truth.npz)."""
        colours = tuple((int(c[0]), int(c[1]), int(c[2])) for c in meta["colours"])
        names = tuple(str(n) for n in meta["names"])
        return cls(grid, names, tuple(float(d) for d in meta["defaults"]), colours)

    def no_go(self, factors: list[FloatArray] | list[list[float]]) -> BoolGrid | None:
        """The cells no robot (of these ``factors``, one per robot) may enter; None: none."""
        if not factors:
            return None
        common = np.logical_and.reduce([np.asarray(f)[self.grid] <= 0.0 for f in factors])
        out: BoolGrid = np.asarray(common, dtype=bool)
        return out if out.any() else None

    def class_at(self, xy: tuple[float, float]) -> int:
        """The class value of the cell holding world point ``xy`` (0 off the map)."""
        row, col = int(np.floor(xy[1])), int(np.floor(xy[0]))
        rows, cols = self.grid.shape
        return int(self.grid[row, col]) if 0 <= row < rows and 0 <= col < cols else 0


def ground_meta(layer: GroundLayer, factors: list[list[float]]) -> dict[str, Any]:
    """What the run log's meta.json holds of the classes (the grid is in truth.npz), with
    each robot's ``factors`` (``Access.factors``) in robot order."""
    return {
        "names": list(layer.names),
        "defaults": list(layer.defaults),
        "colours": [list(c) for c in layer.colours],
        "factors": factors,
    }


def ground_of(spec: GroundSpec | None, shape: tuple[int, int]) -> Ground | None:
    """The true ground classes of ``spec`` on a map of ``shape`` (None without ground).

    Raises:
        ValueError: naming the field (``ground.image``, ``ground.regions[i]``) when the
            image cannot be read, is not the map's size, or a region covers no cell.
    """
    if spec is None:
        return None
    names = spec.names
    grid = np.zeros(shape, dtype=np.uint8)
    if spec.image is not None and spec.legend is not None:
        image = read_colour(spec.image, shape)
        for name, rgb in spec.legend.items():
            grid[(image == np.array(rgb, dtype=np.uint8)).all(axis=2)] = names.index(name) + 1
    regions = spec.regions or []
    for i, cells in regions_cells(regions, shape, "ground.regions"):
        grid[cells] = names.index(regions[i].ground) + 1
    legend = spec.legend or {}
    colours = tuple(tuple(legend.get(n, palette(i))) for i, n in enumerate(names))
    defaults = tuple(spec.classes[n] for n in names)
    return Ground(grid, names, defaults, colours)  # type: ignore[arg-type]


def read_colour(path: Path, shape: tuple[int, int]) -> NDArray[np.uint8]:
    """The RGB pixels of the image at ``path``, which must be the map's size."""
    image = cv2.imread(str(path), cv2.IMREAD_COLOR)
    if image is None:
        raise ValueError(f"ground.image: cannot read the ground image {path}")
    if image.shape[:2] != shape:
        raise ValueError(
            f"ground.image: the ground image {path} is {image.shape[1]}x{image.shape[0]}"
            f" pixels; the map is {shape[1]}x{shape[0]}: give one the size of the map"
        )
    return np.asarray(cv2.cvtColor(image, cv2.COLOR_BGR2RGB), dtype=np.uint8)


PALETTE = ((150, 110, 60), (220, 60, 60), (50, 100, 220), (60, 160, 70), (160, 80, 180))


def palette(i: int) -> tuple[int, int, int]:
    """The colour (RGB) frames shade class ``i`` with when no legend gives one."""
    return PALETTE[i % len(PALETTE)]


@dataclass(frozen=True)
class Access:
    """What one robot can cross: its factor per class value, the true cells it cannot
    enter and the cost multipliers of the cells it crosses slowly (None: none)."""

    factors: FloatArray
    barred: BoolGrid
    slowness: FloatArray | None

    @classmethod
    def of(cls, ground: Ground, crosses: dict[str, float] | None) -> Access:
        """A robot's access to ``ground`` with its ``crosses``."""
        factors = ground.factors(crosses)
        cell = factors[ground.grid]
        barred = cell <= 0.0
        slow = (cell > 0.0) & (cell < 1.0)
        slowness = np.where(slow, 1.0 / np.where(slow, cell, 1.0), 1.0) if slow.any() else None
        barred.flags.writeable = False
        return cls(factors, barred, slowness)

    def enters_barred(self, start: tuple[float, float], end: tuple[float, float]) -> bool:
        """Whether the straight move of the robot's centre from ``start`` to ``end`` takes it
        into a cell it cannot enter (sampled every quarter cell; off the map: no)."""
        length = float(np.hypot(end[0] - start[0], end[1] - start[1]))
        share = np.linspace(0.0, 1.0, int(np.ceil(length * 4)) + 2)[1:]
        cols = np.floor(start[0] + share * (end[0] - start[0])).astype(np.intp)
        rows = np.floor(start[1] + share * (end[1] - start[1])).astype(np.intp)
        inside = (rows >= 0) & (rows < self.barred.shape[0]) & (cols >= 0)
        inside &= cols < self.barred.shape[1]
        return bool(self.barred[rows[inside], cols[inside]].any())

    def factor_at(self, grid: ClassGrid, xy: tuple[float, float]) -> float:
        """The robot's speed factor on the cell holding ``xy`` (1 off the map)."""
        row, col = int(np.floor(xy[1])), int(np.floor(xy[0]))
        rows, cols = grid.shape
        inside = 0 <= row < rows and 0 <= col < cols
        return float(self.factors[grid[row, col]]) if inside else 1.0
