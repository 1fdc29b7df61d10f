"""Procedural maps (phase 0, input data): a request drawn into a map with its base and starts,
and written as files.

:func:`generate` draws a :class:`~.params.MapRequest`: the kind's generator
(``rooms.py``, ``open_ground.py``) from the seed's stream ``map-<kind>``, then the base and
the starts (``place.py``) from the stream ``map-places``. :func:`write_map` writes into a
folder:

* ``map.png``: the map, black walls on white (1 cell = 1 pixel);
* ``map.yaml``: what it is: kind, seed, size, every parameter (defaults filled in), the
  base and the starts, the radius they fit, the open cells, the SHA-256 of the grid
  (row-major, one byte per cell, 1 = wall) and the generator's version;
* ``scenario.yaml``: a scenario running the default team (``frontier``) on it from those
  places, ready for ``mresim run``.

The same request gives the same grid (and ``grid_sha256``) on every machine: every draw is
from the seed's streams, and the geometry is integer.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import yaml

from mresim_phys.mapgen.blueprints import blueprint
from mresim_phys.mapgen.open_ground import cave, rubble
from mresim_phys.mapgen.params import (
    BlueprintParams,
    BuildingParams,
    CaveParams,
    KindParams,
    MapRequest,
    OfficeParams,
    RubbleParams,
)
from mresim_phys.mapgen.place import Point, base_and_starts
from mresim_phys.mapgen.rooms import building, office
from mresim_phys.rng import Streams
from mresim_phys.strict import Strict
from mresim_phys.types import BoolGrid

GENERATOR = 1  # bumped whenever a request would give another map


@dataclass(frozen=True)
class GeneratedMap:
    """A drawn map: its grid, parameters, base and starts."""

    request: MapRequest
    params: Strict  # the kind's parameters (a map file's: where it was read from)
    occupied: BoolGrid
    base: Point
    starts: list[Point]

    @property
    def sha256(self) -> str:
        """SHA-256 of the grid, row-major, one byte per cell (1 = wall)."""
        return hashlib.sha256(self.occupied.astype(np.uint8).tobytes()).hexdigest()


def generate(request: MapRequest) -> GeneratedMap:
    """Draw ``request`` (ValueError naming the parameter if it cannot be drawn)."""
    params = request.kind_params()
    streams = Streams(request.seed)
    rng = streams.get(f"map-{request.kind}")
    size = (request.width, request.height)
    occupied = draw(params, size, rng)
    base, starts = base_and_starts(
        occupied, request.radius, request.robots, streams.get("map-places")
    )
    return GeneratedMap(request, params, occupied, base, starts)


def draw(params: KindParams, size: tuple[int, int], rng: np.random.Generator) -> BoolGrid:
    """The occupancy grid of one kind's ``params`` on a map of ``size`` (width, height)."""
    if isinstance(params, BuildingParams):
        return building(params, *size, rng)
    if isinstance(params, OfficeParams):
        return office(params, *size, rng)
    if isinstance(params, CaveParams):
        return cave(params, *size, rng)
    if isinstance(params, BlueprintParams):
        return blueprint(params, *size)
    assert isinstance(params, RubbleParams)
    return rubble(params, *size, rng)


def write_map(made: GeneratedMap, folder: Path, name: str | None = None) -> list[Path]:
    """``map.png``, ``map.yaml`` and ``scenario.yaml`` (its scenario called ``name``,
    default ``<kind>-<seed>``) in ``folder`` (module docstring)."""
    folder.mkdir(parents=True, exist_ok=True)
    image = np.where(made.occupied, 0, 255).astype(np.uint8)
    png = folder / "map.png"
    if not cv2.imwrite(str(png), image):
        raise OSError(f"cannot write {png}")
    meta, scenario = folder / "map.yaml", folder / "scenario.yaml"
    meta.write_text(yaml.safe_dump(metadata(made), sort_keys=False), encoding="utf-8")
    data = scenario_of(made) | ({"name": name} if name else {})
    scenario.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return [png, meta, scenario]


def metadata(made: GeneratedMap) -> dict[str, Any]:
    """What ``map.yaml`` holds."""
    r = made.request
    return {
        "kind": r.kind,
        "seed": r.seed,
        "size": [r.width, r.height],
        "params": made.params.model_dump(),
        "base": list(made.base),
        "starts": [list(s) for s in made.starts],
        "radius": r.radius,
        "open_cells": int(np.count_nonzero(~made.occupied)),
        "grid_sha256": made.sha256,
        "generator": GENERATOR,
    }


def scenario_of(made: GeneratedMap) -> dict[str, Any]:
    """A scenario running the default team on the map from its base and starts."""
    r = made.request
    reach = max(40.0, 0.25 * max(r.width, r.height))
    return {
        "name": f"{r.kind}-{r.seed}",
        "seed": 0,
        "steps": 4 * (r.width + r.height),
        "stop": {"explored": 0.95},
        "map": {"image": "map.png"},
        "base_station": {"position": list(made.base), "comm_range": reach},
        "team": {"radius": r.radius, "speed": 3, "sensor": {"range": reach}, "comm_range": reach},
        "robots": [{"name": f"R{i + 1}", "start": list(s)} for i, s in enumerate(made.starts)],
    }
