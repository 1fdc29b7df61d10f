"""World (phase 0, events): collapses and falling debris.

* A ``collapse`` event (``{step: 300, collapse: {box: [x0, y0, x1, y1]}}``; a region
  of ``world/shapes.py``: box, circle, polygon or a PNG mask the size of the map)
  turns the region into rubble (``becomes: obstacle``, the default) or clears it
  (``becomes: free``: a wall gives way).
* ``random_debris`` (``{rate, size: [min, max], region, after, until}``): at every
  step from ``after`` to ``until`` a piece of rubble falls with probability ``rate``:
  a square of a side drawn uniformly from ``size`` (cells), centred on a cell drawn
  uniformly from ``region`` (the whole map by default). Every draw comes from the
  debris' own named stream of the scenario seed: the same seed, the same debris.

Rubble never lands on a robot: with ``crush: avoid`` (the default) the cells under
a robot's body stay free, so the rubble lands around it; with ``crush: fail`` the
robot is buried and fails. Rubble is part of the building (the static layer of
``World.set_cells``); it may land on a moving obstacle's cells, which stay covered
by it until it moves on.
"""

from __future__ import annotations

from pathlib import Path
from typing import ClassVar, Protocol

import numpy as np

from mresim_phys.types import BoolGrid
from mresim_phys.world.element_params import Crush, RandomDebrisParams
from mresim_phys.world.footprints import region_cells


class DebrisWorld(Protocol):
    """What falling rubble needs from the run (a part of the events' context)."""

    @property
    def step(self) -> int:
        """The step now starting."""
        ...

    @property
    def shape(self) -> tuple[int, int]:
        """(rows, cols) of the map."""
        ...

    def change_cells(self, cells: BoolGrid, occupied: bool, crush: Crush) -> list[str]:
        """Make the True cells of ``cells`` (a map-sized mask) walls or free; return the
        robots buried (``crush: fail``) or spared (``avoid``)."""
        ...

    def log(self, line: str) -> None:
        """Note what happened this step."""
        ...


def square_at(shape: tuple[int, int], row: int, col: int, side: int) -> BoolGrid:
    """A map-sized mask of the ``side`` x ``side`` square centred on cell (row, col),
    clipped to the map."""
    out = np.zeros(shape, dtype=bool)
    top, left = row - (side - 1) // 2, col - (side - 1) // 2
    out[max(top, 0) : max(top + side, 0), max(left, 0) : max(left + side, 0)] = True
    return out


class RandomDebris:
    """The random debris of a run; :meth:`apply` runs once per step in the events phase."""

    kind: ClassVar[str] = "debris"

    def __init__(self, params: RandomDebrisParams, rng: np.random.Generator,
                 shape: tuple[int, int], base: Path | None = None) -> None:  # fmt: skip
        self.params = params
        self.rng = rng
        region = region_cells(params.region, shape, base) if params.region else None
        self.cells = np.flatnonzero(region) if region is not None else None
        self.shape = shape
        self.fallen = 0

    def apply(self, world: DebrisWorld) -> None:
        """Maybe drop one piece of rubble at this step."""
        p, step = self.params, world.step
        if step < p.after or (p.until is not None and step > p.until):
            return
        falls = self.rng.random() < p.rate  # one draw per step, whatever happens next
        side = int(self.rng.integers(p.size[0], p.size[1] + 1))
        rows, cols = self.shape
        if self.cells is None:
            flat = int(self.rng.integers(rows * cols))
        else:
            flat = int(self.cells[self.rng.integers(len(self.cells))])
        if not falls:
            return
        row, col = divmod(flat, cols)
        robots = world.change_cells(square_at(self.shape, row, col, side), True, p.crush)
        self.fallen += 1
        what = f"debris {side}x{side} at [{col}, {row}]"
        world.log(what + (f" buries {', '.join(robots)}" if robots and p.crush == "fail" else ""))
