"""Benchmark map (output edge): the campus of ``mresim bench --preset campus``, made once.

A 4000 x 4000 building (``mresim make-map building --size 4000x4000 --seed 1``: rooms of
16-40 cells off corridors 10 wide, doors of 8, walls of 2; 14.2 million open cells) is too
large to ship with the package (1 MB of PNG) and quick to draw (a few seconds), so the
benchmark draws it the first time it is asked for and keeps it in the user's cache folder
(``$MRESIM_CACHE``, else ``$XDG_CACHE_HOME/mresim_phys``, else ``~/.cache/mresim_phys``).
The drawing is deterministic (the map's seed and generator version are in its folder's
``map.yaml``), so every machine times the same building; a cached map drawn by another
version of the generator is drawn again.
"""

from __future__ import annotations

import os
from pathlib import Path

import yaml

from mresim_phys.errors import MresimError
from mresim_phys.mapgen.generate import GENERATOR, generate, write_map
from mresim_phys.mapgen.params import MapRequest

CAMPUS_SIZE = 4000
CAMPUS_SEED = 1


def cache_root() -> Path:
    """Where generated benchmark maps are kept (module docstring)."""
    own = os.environ.get("MRESIM_CACHE")
    if own:
        return Path(own)
    xdg = os.environ.get("XDG_CACHE_HOME")
    return (Path(xdg) if xdg else Path.home() / ".cache") / "mresim_phys"


def campus_request() -> MapRequest:
    """The campus building's ``make-map`` request."""
    return MapRequest(kind="building", seed=CAMPUS_SEED, width=CAMPUS_SIZE, height=CAMPUS_SIZE)


def campus_map(root: Path | None = None) -> Path:
    """The campus map's PNG, drawn into ``root`` (default :func:`cache_root`) unless a
    drawing by this generator is there already; MresimError if it cannot be written."""
    folder = (root or cache_root()) / f"campus-{CAMPUS_SIZE}-seed{CAMPUS_SEED}"
    png, meta = folder / "map.png", folder / "map.yaml"
    if png.is_file() and meta.is_file() and drawn_by_this_generator(meta):
        return png
    try:
        write_map(generate(campus_request()), folder, name="campus")
    except OSError as exc:
        raise MresimError(
            f"cannot keep the campus map in {folder} ({exc.strerror or exc}); set MRESIM_CACHE"
            " to a folder you can write, or give a map with --map."
        ) from exc
    return png


def drawn_by_this_generator(meta: Path) -> bool:
    """Whether ``map.yaml`` says its map was drawn by this version of the generator."""
    try:
        data = yaml.safe_load(meta.read_text(encoding="utf-8"))
    except (OSError, yaml.YAMLError):
        return False
    return isinstance(data, dict) and data.get("generator") == GENERATOR
