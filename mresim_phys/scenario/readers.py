"""Phase 0 (input edge): read map files and YAML into plain values.

This is the only module that touches user files on the way in. It turns image maps
(PNG/BMP/GIF/JPEG, dark = obstacle), MRESim text maps (``.txt``: rows, columns, then
rows of ``0``/``1``) and ROS ``map_server`` maps (YAML + PGM/PNG) into a
:class:`LoadedMap` holding a boolean occupancy grid (True = obstacle, image row r = grid
row r), and reads scenario YAML into a mapping. Every user mistake ends in a
:class:`~mresim_phys.errors.MapError` or :class:`~mresim_phys.errors.ScenarioError` whose
one-paragraph message names the file and what to do; no raw PIL/YAML traceback escapes.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from PIL import Image

from mresim_phys.errors import MapError
from mresim_phys.scenario.maps import MAX_MAP_CELLS
from mresim_phys.scenario.yamlfile import read_yaml_file, read_yaml_mapping, require_file
from mresim_phys.types import BoolGrid, FloatArray

__all__ = [
    "LoadedMap",
    "load_image_map",
    "load_map",
    "load_ros_map",
    "load_text_map",
    "read_yaml_mapping",
]

TEXT_FORMAT = (
    "The text map format is: line 1 = number of rows, line 2 = number of columns, then one "
    "line per row made of '0' (free) and '1' (obstacle) characters."
)
IMAGE_HINT = (
    "Use a PNG, BMP, GIF or JPEG image (dark = obstacle), a .txt map in MRESim's text "
    "format, or a ROS map_server .yaml file."
)
_SIXTEEN_BIT_MODES = frozenset({"I", "I;16", "I;16L", "I;16B", "I;16N"})
_IMAGE_ERRORS = (OSError, ValueError, SyntaxError, EOFError)
_ROS_MODES = ("trinary", "scale", "raw")
MAX_RESOLUTION = 1e3  # metres per cell: a ROS map's resolution beyond (or below 1e-6) is a typo
MIN_RESOLUTION = 1e-6


@dataclass(frozen=True)
class LoadedMap:
    """A map as read from disk.

    Attributes:
        occupied: ``(rows, cols)`` bool grid, True = obstacle; row 0 is the top image row.
        resolution: metres per cell if the file says (ROS maps), else None.
        origin: ROS origin ``(x, y, yaw)`` of the lower-left pixel, reported only.
        source: the file the map was read from.
    """

    occupied: BoolGrid
    resolution: float | None
    origin: tuple[float, float, float] | None
    source: Path


def _finish(
    occupied: NDArray[np.bool_],
    source: Path,
    resolution: float | None = None,
    origin: tuple[float, float, float] | None = None,
) -> LoadedMap:
    """Wrap a grid into a :class:`LoadedMap`, rejecting an empty grid."""
    if occupied.ndim != 2 or occupied.size == 0:
        raise MapError(f"Map {source} is empty (shape {occupied.shape}). Use a non-empty map.")
    return LoadedMap(np.ascontiguousarray(occupied, dtype=np.bool_), resolution, origin, source)


def check_map_size(path: Path, what: str, rows: int, cols: int, max_cells: int) -> None:
    """Refuse a map of more than ``max_cells`` cells before anything is allocated for it."""
    if rows * cols > max_cells:
        raise MapError(
            f"{what} {path} is {cols:,} x {rows:,} = {rows * cols:,} cells, over the limit of"
            f" {max_cells:,} (map.max_cells). A world this size needs about"
            f" {rows * cols * 40 / 2**30:.0f} GB; scale the map down, or raise map.max_cells"
            " if you mean it."
        )


@contextmanager
def _opened_image(path: Path, max_cells: int = MAX_MAP_CELLS) -> Iterator[Image.Image]:
    """Open an image fully loaded, turning every Pillow failure into a MapError; an image
    of more than ``max_cells`` pixels is refused from its header, before it is decoded."""
    require_file(path, "Map image", MapError)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)
            with Image.open(path) as img:
                check_map_size(path, "Map image", img.height, img.width, max_cells)
                img.load()
                yield img
    except Image.DecompressionBombError as exc:
        raise MapError(
            f"Map image {path} has more pixels than any map may ({exc}); scale it down."
        ) from None
    except _IMAGE_ERRORS as exc:
        raise MapError(f"Map file {path} is not a readable image ({exc}). {IMAGE_HINT}") from exc


def _grey(img: Image.Image) -> FloatArray:
    """Grey level 0..255 per pixel (Pillow luminance; 16-bit images scaled down)."""
    if img.mode in _SIXTEEN_BIT_MODES:
        return np.asarray(img, dtype=np.float64) / 257.0
    return np.asarray(img.convert("L"), dtype=np.float64)


def _on_white(img: Image.Image) -> Image.Image:
    """Drop transparency by compositing the image on a white background."""
    if img.mode in _SIXTEEN_BIT_MODES or not img.has_transparency_data:
        return img
    rgba = img.convert("RGBA")
    return Image.alpha_composite(Image.new("RGBA", rgba.size, (255, 255, 255, 255)), rgba)


def load_image_map(
    path: Path, threshold: float = 0.5, negate: bool = False, max_cells: int = MAX_MAP_CELLS
) -> LoadedMap:
    """Read an image map: a pixel is an obstacle iff its luminance < ``threshold * 255``.

    Transparent pixels are composited on white first; palette images use their colours.
    With ``negate`` the luminance is inverted (255 - L) first, so bright means obstacle.

    Args:
        path: PNG, BMP, GIF or JPEG file (any size; a GIF's first frame).
        threshold: darkness threshold in (0, 1].
        negate: bright pixels are obstacles instead of dark ones.
        max_cells: the largest map read (width x height); larger is refused unread.

    Returns:
        The map, with ``resolution`` and ``origin`` None.

    Raises:
        MapError: bad threshold, missing or unreadable file, or an empty image.
    """
    path = Path(path)
    if not 0.0 < threshold <= 1.0:
        raise MapError(
            f"Map threshold {threshold!r} for {path} is out of range. Give a number in (0, 1]: "
            "a pixel darker than threshold * 255 is an obstacle."
        )
    with _opened_image(path, max_cells) as img:
        level = _grey(_on_white(img))
    if negate:
        level = 255.0 - level
    return _finish(level < threshold * 255.0, path)


def _text_error(path: Path, line: int, expected: str, found: str) -> MapError:
    return MapError(
        f"Text map {path}, line {line}: expected {expected}, found {found}. {TEXT_FORMAT}"
    )


def _read_text_lines(path: Path, max_cells: int) -> list[str]:
    """Read a text map's lines (LF, CRLF or CR), dropping trailing blank lines; a file too
    big to hold at most ``max_cells`` cells (a cell is a byte, a row ends in at most two)
    is refused unread."""
    require_file(path, "Text map", MapError)
    size = path.stat().st_size
    if size > 3 * max_cells + 64:
        raise MapError(
            f"Text map {path} is {size:,} bytes: more than a map of at most {max_cells:,}"
            " cells (map.max_cells) can take. Scale the map down, or raise map.max_cells."
        )
    try:
        lines = path.read_bytes().decode("utf-8-sig").splitlines()
    except OSError as exc:
        raise MapError(f"Text map {path} cannot be read ({exc}). Check its permissions.") from exc
    except UnicodeDecodeError as exc:
        raise MapError(f"Text map {path} is not a text file ({exc}). {TEXT_FORMAT}") from exc
    while lines and not lines[-1].strip():
        lines.pop()
    return [line.rstrip() for line in lines]


def _header_count(path: Path, lines: list[str], index: int, name: str) -> int:
    """Parse header line ``index`` (0-based) as a positive count of rows or columns."""
    text = lines[index].strip() if index < len(lines) else ""
    try:
        count = int(text)
    except ValueError:
        count = 0
    if count <= 0:
        found = repr(text[:40]) if index < len(lines) else "the end of the file"
        raise _text_error(path, index + 1, f"the number of {name} (a positive integer)", found)
    return count


def _check_row_lengths(path: Path, body: list[str], rows: int, cols: int) -> None:
    """Check the number of row lines and each row's length."""
    for number, line in enumerate(body[:rows], start=3):
        if len(line) != cols:
            raise _text_error(
                path,
                number,
                f"{cols} characters of '0'/'1' (row {number - 2} of {rows})",
                f"{len(line)} characters: {line[:40]!r}",
            )
    if len(body) < rows:
        raise _text_error(
            path, len(body) + 3, f"row {len(body) + 1} of {rows}", "the end of the file"
        )
    if len(body) > rows:
        raise _text_error(
            path, rows + 3, f"the end of the file after {rows} rows", repr(body[rows][:40])
        )


def load_text_map(path: Path, max_cells: int = MAX_MAP_CELLS) -> LoadedMap:
    """Read a map in the original MRESim text format (``1`` = obstacle).

    Args:
        path: the ``.txt`` file.
        max_cells: the largest map read (rows x columns); larger is refused unread.

    Returns:
        The map, with ``resolution`` and ``origin`` None.

    Raises:
        MapError: missing file, bad header, wrong row count or length, or a character
            other than ``0``/``1`` (the message gives the line number).
    """
    path = Path(path)
    lines = _read_text_lines(path, max_cells)
    rows = _header_count(path, lines, 0, "rows")
    cols = _header_count(path, lines, 1, "columns")
    check_map_size(path, "Text map", rows, cols, max_cells)
    body = lines[2:]
    _check_row_lengths(path, body, rows, cols)
    codes = np.frombuffer("".join(body).encode("utf-32-le"), dtype=np.uint32).reshape(rows, cols)
    bad = (codes != ord("0")) & (codes != ord("1"))
    if bad.any():
        row, col = np.argwhere(bad)[0]
        raise _text_error(
            path, int(row) + 3, f"'0' or '1' at column {col + 1}", repr(chr(codes[row, col]))
        )
    return _finish(codes == ord("1"), path)


def _finite(value: float, key: str, path: Path) -> float:
    """``value``, or a MapError when it is not finite (``.nan``, ``.inf``) or beyond 1e9."""
    if not math.isfinite(value) or abs(value) > 1e9:
        raise MapError(f"ROS map {path}: '{key}' must be a finite number, found {value!r}.")
    return value


def _ros_number(meta: dict[str, Any], key: str, path: Path, default: float | None) -> float:
    """Fetch a numeric ROS map key (booleans are not numbers)."""
    value = meta.get(key, default)
    if value is None:
        raise MapError(f"ROS map {path} has no '{key}' key. Add it (see the ROS map_server docs).")
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise MapError(f"ROS map {path}: '{key}' must be a number, found {value!r}.")
    return _finite(float(value), key, path)


def _ros_origin(meta: dict[str, Any], path: Path) -> tuple[float, float, float] | None:
    """Parse the optional ``origin: [x, y, yaw]`` (yaw defaults to 0 if omitted)."""
    origin = meta.get("origin")
    if origin is None:
        return None
    ok = isinstance(origin, list) and len(origin) in (2, 3)
    if not ok or any(isinstance(v, bool) or not isinstance(v, int | float) for v in origin):
        raise MapError(
            f"ROS map {path}: 'origin' must be a list [x, y, yaw] of numbers, found {origin!r}."
        )
    x, y, *yaw = (_finite(float(v), "origin", path) for v in origin)
    return x, y, yaw[0] if yaw else 0.0


def _ros_settings(meta: dict[str, Any], path: Path) -> tuple[float, float, bool, str]:
    """Validate (free_thresh, occupied_thresh, negate, mode) of a ROS map YAML."""
    free = _ros_number(meta, "free_thresh", path, 0.196)
    occ = _ros_number(meta, "occupied_thresh", path, 0.65)
    if not 0.0 <= free <= occ <= 1.0:
        raise MapError(
            f"ROS map {path}: need 0 <= free_thresh <= occupied_thresh <= 1, "
            f"found free_thresh={free}, occupied_thresh={occ}."
        )
    negate = meta.get("negate", 0)
    if negate not in (0, 1):  # also True/False
        raise MapError(f"ROS map {path}: 'negate' must be 0 or 1, found {negate!r}.")
    mode = str(meta.get("mode", "trinary")).lower()
    if mode not in _ROS_MODES:
        raise MapError(
            f"ROS map {path}: 'mode' must be one of {', '.join(_ROS_MODES)}, "
            f"found {meta['mode']!r}."
        )
    return free, occ, bool(negate), mode


def _ros_image_path(meta: dict[str, Any], path: Path) -> Path:
    image = meta.get("image")
    if not isinstance(image, str) or not image:
        raise MapError(
            f"ROS map {path} needs an 'image' key naming the PGM/PNG file "
            "(relative to the YAML file)."
        )
    image_path = path.parent / image
    if not image_path.is_file():
        raise MapError(
            f"ROS map {path} names image '{image}', but {image_path} does not "
            "exist. Put the image next to the YAML file or fix the 'image' key."
        )
    return image_path


def _ros_free(
    grey: FloatArray, opaque: NDArray[np.bool_], free: float, negate: bool, mode: str
) -> NDArray[np.bool_]:
    """ROS semantics reduced to truth: a cell is free iff its occupancy p < free_thresh.

    Occupied (p > occupied_thresh) and unknown cells (in between, or not opaque in scale
    mode) both count as obstacles. Raw mode reads p = value / 100 (values over 100 unknown).
    """
    if mode == "raw":
        value = np.rint(grey)
        return (value <= 100) & (value / 100.0 < free)
    p = grey / 255.0 if negate else (255.0 - grey) / 255.0
    is_free = p < free
    return is_free & opaque if mode == "scale" else is_free


def load_ros_map(yaml_path: Path, max_cells: int = MAX_MAP_CELLS) -> LoadedMap:
    """Read a ROS ``map_server`` map (YAML + the PGM/PNG it names).

    Keys: ``image`` (relative to the YAML), ``resolution``, optional ``origin``,
    ``negate`` (0), ``occupied_thresh`` (0.65), ``free_thresh`` (0.196), ``mode``
    (trinary, scale or raw). Other keys are ignored. The image orientation is kept
    (image row 0 = grid row 0); unknown cells count as obstacles.

    Raises:
        MapError: missing/invalid YAML or keys, or a missing/unreadable image.
    """
    path = Path(yaml_path)
    meta = read_yaml_file(path, "ROS map file", MapError)
    resolution = _ros_number(meta, "resolution", path, None)
    if not MIN_RESOLUTION <= resolution <= MAX_RESOLUTION:
        raise MapError(
            f"ROS map {path}: 'resolution' must be metres per cell from {MIN_RESOLUTION:g} to"
            f" {MAX_RESOLUTION:g}, found {resolution!r}."
        )
    origin = _ros_origin(meta, path)
    free, _, negate, mode = _ros_settings(meta, path)
    with _opened_image(_ros_image_path(meta, path), max_cells) as img:
        opaque = np.ones((img.height, img.width), dtype=bool)
        if img.has_transparency_data:
            opaque = np.asarray(img.convert("RGBA"))[:, :, 3] == 255
        grey = _grey(img)
    return _finish(~_ros_free(grey, opaque, free, negate, mode), path, resolution, origin)


def load_map(
    path: Path, threshold: float = 0.5, negate: bool = False, max_cells: int = MAX_MAP_CELLS
) -> LoadedMap:
    """Read any supported map, choosing the loader by file suffix.

    ``.txt`` -> :func:`load_text_map`, ``.yaml``/``.yml`` -> :func:`load_ros_map`,
    anything else -> :func:`load_image_map` (``threshold`` and ``negate`` apply there only).
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".txt":
        return load_text_map(path, max_cells)
    if suffix in (".yaml", ".yml"):
        return load_ros_map(path, max_cells)
    return load_image_map(path, threshold, negate, max_cells)
