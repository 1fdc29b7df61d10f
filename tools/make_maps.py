"""Phase 0 data generator: write the shipped maps in ``maps/`` deterministically.

Run ``python tools/make_maps.py`` from the repository root to (re)write ``maps/office.png``,
``maps/small_rooms.png``, ``maps/cave.txt``, ``maps/warehouse.yaml`` + ``warehouse.pgm``,
``maps/maze.png``, ``maps/rubble.png`` and ``maps/README.md``, then load each file back
with :mod:`mresim_phys.io` and check that the suggested start positions are free, at least
4 cells from any wall, and in one big connected free region. Geometry is fixed; the maze
and the rubble use NumPy generators with fixed seeds, so every run writes the same bytes.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray
from PIL import Image
from scipy import ndimage

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from mresim_phys.scenario.readers import LoadedMap, load_map  # noqa: E402
from mresim_phys.world.maps import free_components_mask  # noqa: E402

Image8 = NDArray[np.uint8]
WALL, FREE, UNKNOWN = 0, 255, 205
ROS_FREE = 254
MIN_CLEARANCE = 4.0  # cells between a start cell's boundary and the nearest wall cell


@dataclass(frozen=True)
class MapInfo:
    """One shipped map: its file, a description and suggested starts (x = col, y = row)."""

    file: str
    what: str
    robots: tuple[tuple[int, int], ...]
    base: tuple[int, int]


MAPS = {
    "office": MapInfo(
        "office.png",
        "L-shaped office floor: corridor, two rows of rooms, lobby with a round pillar, "
        "diagonal storage wall, stair core, furniture",
        ((40, 300), (50, 300), (60, 300), (70, 300)),
        (25, 300),
    ),
    "small_rooms": MapInfo(
        "small_rooms.png",
        "four corner rooms (12 px doors) around a cross-shaped hall with a table",
        ((66, 52), (66, 68), (94, 52), (94, 68)),
        (20, 60),
    ),
    "cave": MapInfo(
        "cave.txt",
        "five irregular chambers joined by tunnels, rock pillars (MRESim text format)",
        ((50, 50), (50, 61), (67, 48), (72, 54)),
        (49, 55),
    ),
    "warehouse": MapInfo(
        "warehouse.yaml",
        "ROS map_server map (0.05 m/cell): shelf aisles, loading dock with pallets, "
        "office; unknown (205) outside the outer wall",
        ((245, 60), (255, 60), (265, 60), (275, 60)),
        (260, 100),
    ),
    "maze": MapInfo(
        "maze.png",
        "maze-like building: 20 x 15 rooms on a 30-cell pitch, 2-cell walls, 10-14 cell "
        "doors, loops (15% extra doors), open 2 x 2 lobby at the top left",
        ((15, 15), (30, 15), (45, 15), (15, 45), (45, 45)),
        (30, 30),
    ),
    "rubble": MapInfo(
        "rubble.png",
        "collapsed site: open area with broken wall remnants and 120 rubble pieces "
        "(discs, rotated slabs, polygons); enclosed pockets filled",
        ((20, 380), (32, 380), (44, 380), (56, 380), (20, 366)),
        (40, 360),
    ),
}


def box(img: Image8, x0: int, y0: int, x1: int, y1: int, value: int = WALL) -> None:
    """Fill cells x in [x0, x1), y in [y0, y1) with ``value``."""
    img[y0:y1, x0:x1] = value


def ring(img: Image8, x0: int, y0: int, x1: int, y1: int, thick: int) -> None:
    """Draw a wall of ``thick`` cells just inside the rectangle [x0, x1) x [y0, y1)."""
    box(img, x0, y0, x1, y0 + thick)
    box(img, x0, y1 - thick, x1, y1)
    box(img, x0, y0, x0 + thick, y1)
    box(img, x1 - thick, y0, x1, y1)


def _office_shell(img: Image8) -> None:
    """L-shaped footprint (outside solid), 3 px exterior wall, corridor and room walls."""
    box(img, 13, 43, 787, 557, FREE)
    box(img, 587, 427, 790, 560)  # the notch outside the L
    ring(img, 10, 40, 790, 560, 3)
    box(img, 13, 277, 787, 280)  # corridor walls: corridor is y in [280, 320)
    box(img, 13, 320, 787, 323)
    for x in (110, 210, 330, 430, 530, 650):  # top row partitions
        box(img, x, 43, x + 3, 277)
    for x in (130, 260, 400, 520):  # bottom row partitions
        box(img, x, 323, x + 3, 557)
    box(img, 650, 323, 653, 427)


def _office_doors(img: Image8) -> None:
    """16 px doors from every room to the corridor, plus the open lobby."""
    for x in (50, 150, 262, 372, 470, 580, 700, 740):
        box(img, x, 277, x + 16, 280, FREE)
    for x in (80, 330, 450, 550, 610, 700):
        box(img, x, 320, x + 16, 323, FREE)
    box(img, 150, 320, 240, 323, FREE)  # lobby: open to the corridor
    box(img, 520, 470, 523, 488, FREE)  # door between two bottom rooms


def _office_furniture(img: Image8) -> None:
    """Stair core, desks, shelves, a table, a round pillar and a diagonal wall."""
    box(img, 13, 323, 73, 420)  # stair and lift core (solid)
    for x in (25, 125, 230, 350, 450, 550):  # desks against the top wall
        box(img, x, 60, x + 50, 85)
    for x in (280, 420, 540):
        box(img, x - 10, 180, x + 30, 200)
    box(img, 290, 440, 380, 470)  # meeting table
    for y in (350, 390, 430, 470, 510):  # library shelves
        box(img, 420, y, 500, y + 6)
    box(img, 610, 100, 640, 240)  # server racks
    box(img, 670, 200, 730, 225)
    box(img, 680, 350, 770, 370)
    cv2.circle(img, (195, 420), 12, WALL, thickness=-1)  # round pillar in the lobby
    cv2.line(img, (700, 43), (787, 130), WALL, thickness=3)  # diagonal storage wall
    box(img, 737, 78, 751, 94, FREE)  # door into the triangular store


def office() -> Image8:
    """800 x 600 office floor plan (0 = wall, 255 = free)."""
    img = np.zeros((600, 800), dtype=np.uint8)
    _office_shell(img)
    _office_doors(img)
    _office_furniture(img)
    return img


def small_rooms() -> Image8:
    """160 x 120: four corner rooms with 12 px doors around a central hall."""
    img = np.full((120, 160), FREE, dtype=np.uint8)
    ring(img, 0, 0, 160, 120, 2)
    for x in (58, 100):  # room side walls
        box(img, x, 0, x + 2, 47)
        box(img, x, 73, x + 2, 120)
    box(img, 0, 45, 60, 47)
    box(img, 100, 45, 160, 47)
    box(img, 0, 73, 60, 75)
    box(img, 100, 73, 160, 75)
    box(img, 20, 45, 32, 47, FREE)  # doors
    box(img, 100, 15, 102, 27, FREE)
    box(img, 58, 90, 60, 102, FREE)
    box(img, 125, 73, 137, 75, FREE)
    box(img, 76, 56, 84, 64)  # table in the hall
    return img


def _blob(centre: tuple[int, int], radii: tuple[int, int], phase: float) -> NDArray[np.int32]:
    """Polygon of an ellipse with a wavy rim (fixed harmonics, no randomness)."""
    theta = np.linspace(0, 2 * np.pi, 96, endpoint=False)
    wobble = 1 + 0.12 * np.sin(3 * theta + phase) + 0.07 * np.sin(7 * theta + 2 * phase)
    x = centre[0] + radii[0] * wobble * np.cos(theta)
    y = centre[1] + radii[1] * wobble * np.sin(theta)
    return np.round(np.column_stack((x, y))).astype(np.int32)


def cave() -> NDArray[np.bool_]:
    """120 x 90 cave: True = rock."""
    img = np.zeros((90, 120), dtype=np.uint8)
    chambers = {"a": (24, 22), "b": (88, 20), "c": (60, 55), "d": (20, 70), "e": (100, 70)}
    radii = {"a": (17, 13), "b": (22, 11), "c": (19, 15), "d": (13, 11), "e": (14, 12)}
    for k, (name, centre) in enumerate(chambers.items()):
        cv2.fillPoly(img, [_blob(centre, radii[name], 0.9 * k)], FREE)
    for a, b, width in (("a", "c", 6), ("b", "c", 5), ("c", "d", 5), ("c", "e", 7), ("a", "b", 4)):
        cv2.line(img, chambers[a], chambers[b], FREE, thickness=width)
    for centre, radius in (((60, 55), 4), ((92, 18), 3), ((20, 74), 2), ((104, 66), 3)):
        cv2.circle(img, centre, radius, WALL, thickness=-1)
    ring(img, 0, 0, 120, 90, 2)
    return img == WALL


def warehouse() -> Image8:
    """300 x 200 ROS image: 0 wall, 254 free, 205 unknown outside the outer wall."""
    img = np.full((200, 300), UNKNOWN, dtype=np.uint8)
    box(img, 12, 12, 288, 188, ROS_FREE)
    ring(img, 10, 10, 290, 190, 2)
    for y in range(34, 170, 18):  # shelf racks 4 cells deep, aisles 14 wide, cross aisles
        box(img, 30, y, 105, y + 4)
        box(img, 119, y, 210, y + 4)
    box(img, 225, 12, 227, 130)  # dock partition, two openings
    box(img, 225, 40, 227, 56, ROS_FREE)
    box(img, 225, 100, 227, 116, ROS_FREE)
    for x, y in ((240, 85), (260, 85), (240, 115), (262, 118)):  # pallets
        box(img, x, y, x + 10, y + 8)
    ring(img, 230, 140, 290, 190, 2)  # office in the corner
    box(img, 240, 140, 254, 142, ROS_FREE)
    return img


MAZE_PITCH = 30  # cells from one maze wall centre line to the next
MAZE_WALL = 2  # interior wall thickness (the outer wall is 3)
MAZE_DOOR = (10, 14)  # door widths, inclusive
MAZE_LOOPS = 0.15  # share of the spanning tree's closed walls that get a door as well
MAZE_SEED = 20240607
Wall = tuple[str, int, int]  # ("v", i, j): x = i * pitch, row j; ("h", i, j): y = j * pitch


def _maze_tree(cols: int, rows: int, rng: np.random.Generator) -> list[Wall]:
    """Walls opened by a depth-first (recursive backtracker) spanning tree of the rooms."""
    seen = np.zeros((rows, cols), dtype=bool)
    seen[0, 0] = True
    stack, opened = [(0, 0)], []
    while stack:
        c, r = stack[-1]
        options = [
            (c + dc, r + dr)
            for dc, dr in ((1, 0), (-1, 0), (0, 1), (0, -1))
            if 0 <= c + dc < cols and 0 <= r + dr < rows and not seen[r + dr, c + dc]
        ]
        if not options:
            stack.pop()
            continue
        nc, nr = options[int(rng.integers(len(options)))]
        seen[nr, nc] = True
        opened.append(("v", max(c, nc), r) if nr == r else ("h", c, max(r, nr)))
        stack.append((nc, nr))
    return opened


def _maze_doors(cols: int, rows: int, rng: np.random.Generator) -> list[Wall]:
    """The tree's walls plus ``MAZE_LOOPS`` of the others (so the maze has loops)."""
    tree = _maze_tree(cols, rows, rng)
    walls = [("v", i, j) for i in range(1, cols) for j in range(rows)]
    walls += [("h", i, j) for j in range(1, rows) for i in range(cols)]
    opened = set(tree)
    closed = [w for w in walls if w not in opened]
    extra = rng.choice(len(closed), size=round(MAZE_LOOPS * len(closed)), replace=False)
    return tree + [closed[k] for k in sorted(extra.tolist())]


def maze() -> Image8:
    """600 x 450 maze-like building: every room reachable, some loops."""
    height, width, p, half = 450, 600, MAZE_PITCH, MAZE_WALL // 2
    cols, rows = width // p, height // p
    img = np.full((height, width), FREE, dtype=np.uint8)
    ring(img, 0, 0, width, height, 3)
    for i in range(1, cols):
        box(img, i * p - half, 0, i * p + half, height)
    for j in range(1, rows):
        box(img, 0, j * p - half, width, j * p + half)
    rng = np.random.default_rng(MAZE_SEED)
    for kind, i, j in _maze_doors(cols, rows, rng):
        k, rooms = (j, rows) if kind == "v" else (i, cols)  # the room index along the wall
        lo = k * p + half if k > 0 else 3  # the wall's free span between its corners
        hi = (k + 1) * p - half if k + 1 < rooms else (k + 1) * p - 3
        door = int(rng.integers(MAZE_DOOR[0], MAZE_DOOR[1] + 1))
        start = lo + 2 + int(rng.integers(0, hi - lo - 4 - door + 1))  # 2 cells from corners
        at = (i if kind == "v" else j) * p
        if kind == "v":
            box(img, at - half, start, at + half, start + door, FREE)
        else:
            box(img, start, at - half, start + door, at + half, FREE)
    box(img, 3, 3, 2 * p - half, 2 * p - half, FREE)  # the lobby: rooms (0..1, 0..1) merged
    return img


RUBBLE_PIECES = 120
RUBBLE_SEED = 20240608
RUBBLE_CLEAR = (3, 330, 90, 397)  # x0, y0, x1, y1: the start area, kept free of rubble
RUBBLE_WALLS = (  # broken wall remnants: (x0, y0, x1, y1, thickness) per standing piece
    (40, 110, 130, 112, 4),
    (148, 113, 215, 117, 4),
    (236, 118, 300, 121, 3),
    (340, 30, 342, 105, 4),
    (343, 125, 346, 200, 4),
    (347, 222, 350, 268, 3),
    (150, 200, 150, 280, 4),
    (150, 280, 210, 282, 4),
    (232, 283, 265, 284, 3),
    (395, 330, 440, 290, 4),
    (455, 276, 485, 250, 4),
)


def _rubble_piece(img: Image8, rng: np.random.Generator, cx: int, cy: int) -> None:
    """Draw one piece of rubble at (cx, cy): a disc, a rotated slab or a small polygon."""
    kind = int(rng.integers(3))
    if kind == 0:
        cv2.circle(img, (cx, cy), int(rng.integers(2, 7)), WALL, thickness=-1)
        return
    if kind == 1:
        size = (float(rng.integers(4, 15)), float(rng.integers(3, 8)))
        corners = cv2.boxPoints(((float(cx), float(cy)), size, float(rng.integers(0, 180))))
    else:
        n = int(rng.integers(3, 7))  # corners at jittered, evenly spread angles: no slivers
        theta = (np.arange(n) + rng.uniform(-0.25, 0.25, n)) * (2 * np.pi / n) + rng.uniform(0, 7)
        radius = rng.uniform(3, 7, n)
        corners = np.column_stack((cx + radius * np.cos(theta), cy + radius * np.sin(theta)))
    cv2.fillPoly(img, [np.round(corners).astype(np.int32)], WALL)


def rubble() -> Image8:
    """500 x 400 collapsed site; free pockets cut off from the starts are filled."""
    height, width = 400, 500
    img = np.full((height, width), FREE, dtype=np.uint8)
    ring(img, 0, 0, width, height, 3)
    for x0, y0, x1, y1, thick in RUBBLE_WALLS:
        cv2.line(img, (x0, y0), (x1, y1), WALL, thickness=thick)
    rng = np.random.default_rng(RUBBLE_SEED)
    x0, y0, x1, y1 = RUBBLE_CLEAR
    placed = 0
    while placed < RUBBLE_PIECES:
        cx, cy = int(rng.integers(6, width - 6)), int(rng.integers(6, height - 6))
        if x0 - 8 <= cx < x1 + 8 and y0 - 8 <= cy < y1 + 8:
            continue  # keep the start area clear
        _rubble_piece(img, rng, cx, cy)
        placed += 1
    labels, _ = ndimage.label(img == FREE)  # default structure: 4-connected
    x, y = MAPS["rubble"].base
    img[(labels != labels[y, x]) & (img == FREE)] = WALL
    return img


ROS_YAML = """image: warehouse.pgm
resolution: 0.05
origin: [-7.5, -5.0, 0.0]
negate: 0
occupied_thresh: 0.65
free_thresh: 0.196
mode: trinary
"""


def write_all(out: Path) -> None:
    """Write every map file into ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    Image.fromarray(office()).save(out / "office.png", optimize=True)
    Image.fromarray(small_rooms()).save(out / "small_rooms.png", optimize=True)
    rock = cave()
    rows = "\n".join("".join("1" if v else "0" for v in row) for row in rock)
    (out / "cave.txt").write_text(f"{rock.shape[0]}\n{rock.shape[1]}\n{rows}\n")
    Image.fromarray(warehouse()).save(out / "warehouse.pgm")
    (out / "warehouse.yaml").write_text(ROS_YAML)
    Image.fromarray(maze()).save(out / "maze.png", optimize=True)
    Image.fromarray(rubble()).save(out / "rubble.png", optimize=True)


def clearance(occupied: NDArray[np.bool_]) -> NDArray[np.float64]:
    """Distance from each cell centre to the nearest obstacle cell (outside = obstacle) - 0.5."""
    padded = np.pad(~occupied, 1, constant_values=False)
    return ndimage.distance_transform_edt(padded)[1:-1, 1:-1] - 0.5


class MapCheckError(RuntimeError):
    """A shipped map fails its start-position or connectivity check."""


@dataclass(frozen=True)
class MapStats:
    """Figures for the README table."""

    rows: int
    cols: int
    free: int
    reachable: int


def check(name: str, loaded: LoadedMap) -> MapStats:
    """Check the suggested starts of map ``name``; return its statistics.

    Raises:
        MapCheckError: a start is too close to a wall, the starts are not connected, or
            less than 95% of the free cells are reachable from them.
    """
    info, grid = MAPS[name], loaded.occupied
    points = [*info.robots, info.base]
    room = clearance(grid)
    for x, y in points:
        if room[y, x] < MIN_CLEARANCE:
            raise MapCheckError(f"{name}: start ({x}, {y}) is {room[y, x]:.1f} from a wall")
    reach = free_components_mask(grid, [(x + 0.5, y + 0.5) for x, y in points])
    for x, y in points:
        alone = free_components_mask(grid, (x + 0.5, y + 0.5))
        if alone.sum() != reach.sum():
            raise MapCheckError(f"{name}: start ({x}, {y}) is not connected to the others")
    free = int((~grid).sum())
    if reach.sum() < 0.95 * free:
        raise MapCheckError(f"{name}: only {reach.sum()} of {free} free cells are reachable")
    return MapStats(grid.shape[0], grid.shape[1], free, int(reach.sum()))


def readme(stats: dict[str, MapStats]) -> str:
    """The text of ``maps/README.md``."""
    rows = []
    for name, s in stats.items():
        info = MAPS[name]
        robots = ", ".join(f"({x}, {y})" for x, y in info.robots)
        share = 100 * s.free / (s.rows * s.cols)
        rows.append(
            f"| `{info.file}` | {s.cols} x {s.rows} | {s.free:,} ({share:.0f}%) | "
            f"{s.reachable:,} | {info.what} | {robots} | {info.base} |"
        )
    return README_TEMPLATE.format(table="\n".join(rows), clearance=int(MIN_CLEARANCE))


README_TEMPLATE = """# Shipped maps

Generated by `python tools/make_maps.py` (fixed geometry; the maze and the rubble come from
fixed random seeds, so the files are the same on every run); do not edit the files by
hand, change the generator and rerun it. The script also loads each map back and checks
the start positions below.

| file | cols x rows | free cells | reachable | what it is | robot starts (x, y) | base (x, y) |
|---|---|---|---|---|---|---|
{table}

Every start and base position is a free cell at least {clearance} cells from any wall, and
all of a map's positions lie in the same connected free region ("reachable" counts the
free cells 4-connected to the starts: the denominator of the explored-area metric).

## Cell convention

A map is a grid indexed `[row, col]`. Cell (row r, col c) covers x in [c, c+1) and
y in [r, r+1) in world units (cells), so its centre is (c + 0.5, r + 0.5): x = column
(growing right), y = row (growing down, as in the image). Positions above are cells
(x = col, y = row); place a robot at the cell centre. Everything outside the grid counts
as obstacle, so every map is closed.

## Formats

- **Images** (`.png`, `.bmp`, `.gif`, `.jpg`; any size): a pixel is an obstacle iff its
  luminance is below `threshold * 255` (default threshold 0.5, i.e. dark = obstacle);
  `negate` makes bright pixels obstacles. Transparent pixels count as white. Image row r is
  grid row r. `office.png`, `small_rooms.png`, `maze.png` and `rubble.png` are black (0)
  on white (255).
- **MRESim text** (`.txt`): line 1 = number of rows, line 2 = number of columns, then one
  line per row of `0` (free) / `1` (obstacle) characters; LF or CRLF. `cave.txt` is 90 rows
  of 120 columns.
- **ROS map_server** (`.yaml` naming a PGM/PNG next to it): standard keys `image`,
  `resolution` (metres per cell), `origin` [x, y, yaw] (reported only), `negate`,
  `occupied_thresh`, `free_thresh`, `mode` (trinary, scale, raw). With negate 0 a pixel's
  occupancy is p = (255 - v) / 255: free if p < free_thresh, occupied if
  p > occupied_thresh, unknown in between. Unknown counts as obstacle in the ground truth.
  The image orientation is kept (image row 0 = grid row 0). `warehouse.pgm` uses 254 free,
  0 occupied and 205 unknown (outside the building), at 0.05 m per cell (15 m x 10 m).
"""

BUILDERS: dict[str, Callable[[], object]] = {
    "office": office,
    "small_rooms": small_rooms,
    "cave": cave,
    "warehouse": warehouse,
    "maze": maze,
    "rubble": rubble,
}


def main(argv: list[str] | None = None) -> int:
    """Write the maps (unless ``--check-only``), check them and write the README."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "maps", help="output folder")
    parser.add_argument("--check-only", action="store_true", help="only check existing files")
    args = parser.parse_args(argv)
    if not args.check_only:
        write_all(args.out)
    try:
        stats = {name: check(name, load_map(args.out / info.file)) for name, info in MAPS.items()}
    except MapCheckError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    for name, s in stats.items():
        print(f"{name:12s} {s.cols}x{s.rows} free {s.free} reachable {s.reachable}")
    if not args.check_only:
        (args.out / "README.md").write_text(readme(stats))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
