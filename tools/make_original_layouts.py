"""Draw ``maps/library.png`` and ``maps/rooms.png``: two of the original MRESim's layouts.

The original Java MRESim ships ``environments/library.png`` and ``environments/rooms.png``
(800 x 600, one pixel = one cell). Those images may not be redistributed, so this script
redraws the same layouts from a vector description kept in ``tools/original_layouts.yaml``
(the building's outline as polygons, axis-aligned walls as rectangles, diagonal walls as
thick segments; traced once from the originals). It never reads the originals.

Run ``python tools/make_original_layouts.py`` from the repository root to (re)write both
images (same bytes on every run), load them back with :mod:`mresim_phys.io`, check their
start positions with ``make_maps.check`` and put their rows into ``maps/README.md``'s
table. ``tools/make_maps.py`` rewrites that README without these rows: run this script
after it.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import yaml
from numpy.typing import NDArray
from PIL import Image

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import make_maps  # noqa: E402  (puts the repository root on sys.path)
from make_maps import FREE, ROOT, WALL, MapCheckError, MapInfo, MapStats  # noqa: E402

from mresim_phys.scenario.readers import load_map  # noqa: E402

Image8 = NDArray[np.uint8]
Point = tuple[int, int]
Rect = tuple[int, int, int, int]  # x0, y0, x1, y1: the pixels x0 <= x < x1, y0 <= y < y1
Segment = tuple[float, float, float, float, float]  # x0, y0, x1, y1, thickness

LAYOUT_FILE = HERE / "original_layouts.yaml"
SOURCE = (
    "redrawn from the layout of the original MRESim's environments/{}, for comparisons "
    "with the original"
)

MAPS = {
    "library": MapInfo(
        "library.png",
        SOURCE.format("library.png") + ": a library floor, many small rooms (3 px walls), an "
        "octagonal north-west wing, black exterior",
        ((430, 520), (390, 520), (410, 520), (390, 500)),
        (380, 520),
    ),
    "rooms": MapInfo(
        "rooms.png",
        SOURCE.format("rooms.png") + ": a corridor with two rows of rooms, a west column of "
        "rooms and a central block (5 px walls), black exterior",
        ((330, 520), (350, 520), (390, 520), (410, 520)),
        (370, 520),
    ),
}

NOTE = (
    "`library.png` and `rooms.png` are drawn by `python tools/make_original_layouts.py` from\n"
    "the vector layout in `tools/original_layouts.yaml` (outline polygons, wall rectangles,\n"
    "diagonal wall segments), traced once from the original MRESim's images, which are not\n"
    "shipped. Measured against the originals: free cells within 0.1%, pixel agreement\n"
    "99.9% (library) and 100% (rooms), the same connected free regions before and after a\n"
    "1-cell erosion. Both are black (0) on white (255). `tools/make_maps.py` rewrites this\n"
    "file without them: rerun `tools/make_original_layouts.py` after it."
)


@dataclass(frozen=True)
class Layout:
    """One map's vector description (pixel coordinates: x = column, y = row)."""

    size: Point  # width, height
    outline: tuple[tuple[Point, ...], ...]  # footprint polygons; black outside
    rects: tuple[Rect, ...]
    segments: tuple[Segment, ...]


def _ints(values: object, count: int, what: str) -> tuple[int, ...]:
    """``values`` as a tuple of ``count`` ints, or a ValueError naming ``what``."""
    if not isinstance(values, list) or len(values) != count:
        raise ValueError(f"{what}: expected a list of {count} numbers, got {values!r}")
    if not all(isinstance(v, int) and not isinstance(v, bool) for v in values):
        raise ValueError(f"{what}: expected whole pixel coordinates, got {values!r}")
    return tuple(values)


def _list(value: object, what: str) -> list[object]:
    """``value`` if it is a list (a missing entry is an empty one), or a ValueError."""
    if value is None:
        return []
    if not isinstance(value, list):
        raise ValueError(f"{what}: expected a list, got {value!r}")
    return value


def _segment(values: object, what: str) -> Segment:
    """One diagonal wall ``[x0, y0, x1, y1, thickness]``, or a ValueError."""
    numbers = _list(values, what)
    if len(numbers) != 5 or not all(isinstance(v, int | float) for v in numbers):
        raise ValueError(f"{what}: expected [x0, y0, x1, y1, thickness], got {values!r}")
    x0, y0, x1, y1, thick = (float(v) for v in numbers)  # type: ignore[arg-type]
    if (x0, y0) == (x1, y1) or thick <= 0:
        raise ValueError(f"{what}: {values!r} has no length or no thickness")
    return (x0, y0, x1, y1, thick)


def parse_layout(name: str, data: dict[str, object]) -> Layout:
    """Check one map's entry of the YAML file and turn it into a :class:`Layout`."""
    width, height = _ints(data.get("size"), 2, f"{name}.size")
    outline = []
    for k, polygon in enumerate(_list(data.get("outline"), f"{name}.outline")):
        corners = [_ints(p, 2, f"{name}.outline[{k}]") for p in _list(polygon, name)]
        if len(corners) < 3:
            raise ValueError(f"{name}.outline[{k}]: expected at least 3 corners")
        outline.append(tuple((x, y) for x, y in corners))
    if not outline:
        raise ValueError(f"{name}.outline: expected at least one polygon")
    rects = []
    for k, values in enumerate(_list(data.get("rects"), f"{name}.rects")):
        x0, y0, x1, y1 = _ints(values, 4, f"{name}.rects[{k}]")
        if not (0 <= x0 < x1 <= width and 0 <= y0 < y1 <= height):
            raise ValueError(f"{name}.rects[{k}] {values} is empty or outside the image")
        rects.append((x0, y0, x1, y1))
    segments = [
        _segment(values, f"{name}.segments[{k}]")
        for k, values in enumerate(_list(data.get("segments"), f"{name}.segments"))
    ]
    return Layout((width, height), tuple(outline), tuple(rects), tuple(segments))


def load_layouts(path: Path = LAYOUT_FILE) -> dict[str, Layout]:
    """Every map described in ``path`` (``original_layouts.yaml``), by name."""
    data = yaml.safe_load(path.read_text(encoding="utf-8"))
    if not isinstance(data, dict) or set(data) != set(MAPS):
        raise ValueError(f"{path}: expected exactly the maps {sorted(MAPS)}")
    for name in MAPS:
        if not isinstance(data[name], dict):
            raise ValueError(f"{path}: {name} is not a mapping")
    return {name: parse_layout(name, data[name]) for name in MAPS}


def draw_segment(img: Image8, segment: Segment) -> None:
    """Paint a thick straight wall: pixel centres within thickness / 2 of the line, flat ends."""
    x0, y0, x1, y1, thick = segment
    height, width = img.shape
    reach = int(np.ceil(thick / 2)) + 1
    cols = np.arange(max(int(min(x0, x1)) - reach, 0), min(int(max(x0, x1)) + reach + 1, width))
    rows = np.arange(max(int(min(y0, y1)) - reach, 0), min(int(max(y0, y1)) + reach + 1, height))
    ys, xs = np.meshgrid(rows, cols, indexing="ij")
    dx, dy = x1 - x0, y1 - y0
    length = float(np.hypot(dx, dy))
    along = ((xs - x0) * dx + (ys - y0) * dy) / length
    across = np.abs((xs - x0) * dy - (ys - y0) * dx) / length
    inside = (across <= thick / 2) & (along >= 0) & (along <= length)
    img[ys[inside], xs[inside]] = WALL


def draw(layout: Layout) -> Image8:
    """The map image: black outside the outline, white inside, walls black."""
    width, height = layout.size
    img = np.full((height, width), WALL, dtype=np.uint8)
    cv2.fillPoly(img, [np.array(p, dtype=np.int32) for p in layout.outline], FREE)
    for x0, y0, x1, y1 in layout.rects:
        img[y0:y1, x0:x1] = WALL
    for segment in layout.segments:
        draw_segment(img, segment)
    return img


def write_all(out: Path, layouts: dict[str, Layout]) -> None:
    """Write every map image into ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    for name, layout in layouts.items():
        Image.fromarray(draw(layout)).save(out / MAPS[name].file, optimize=True)


def check_all(out: Path) -> dict[str, MapStats]:
    """Load the maps back and check their starts with ``make_maps.check``.

    ``make_maps.check`` and ``make_maps.readme`` look maps up in ``make_maps.MAPS``, so
    this registers the two maps there (in this process only).
    """
    make_maps.MAPS.update(MAPS)
    return {name: make_maps.check(name, load_map(out / info.file)) for name, info in MAPS.items()}


def table_rows(stats: dict[str, MapStats]) -> list[str]:
    """The README table rows of these maps, formatted by ``make_maps.readme``."""
    return [line for line in make_maps.readme(stats).splitlines() if line.startswith("| `")]


def update_readme(text: str, rows: list[str]) -> str:
    """``text`` (``maps/README.md``) with ``rows`` at the end of its table and :data:`NOTE`.

    Rows of these maps already in the table are replaced, so reruns change nothing.
    """
    files = tuple(f"| `{info.file}` |" for info in MAPS.values())
    lines = [line for line in text.splitlines() if not line.startswith(files)]
    table = [k for k, line in enumerate(lines) if line.startswith("| `")]
    if not table:
        raise ValueError("maps/README.md has no map table")
    end = table[-1] + 1
    lines[end:end] = rows
    body = "\n".join(lines) + "\n"
    if NOTE not in body:
        after = "\n".join(lines[: end + len(rows)])
        body = after + "\n\n" + NOTE + body[len(after) :]
    return body


def main(argv: list[str] | None = None) -> int:
    """Write the maps (unless ``--check-only``), check them and update the README."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "maps", help="output folder")
    parser.add_argument("--check-only", action="store_true", help="only check existing files")
    args = parser.parse_args(argv)
    if not args.check_only:
        write_all(args.out, load_layouts())
    try:
        stats = check_all(args.out)
    except MapCheckError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    for name, s in stats.items():
        print(f"{name:12s} {s.cols}x{s.rows} free {s.free} reachable {s.reachable}")
    readme = args.out / "README.md"
    if not args.check_only and readme.exists():
        readme.write_text(update_readme(readme.read_text(encoding="utf-8"), table_rows(stats)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
