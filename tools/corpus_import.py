"""Phase 0 data import (offline): turn public building maps into ``maps/corpus/``.

``python tools/corpus_import.py --src DIR`` reads each source map of :data:`SOURCES` from
``DIR/<owner>/<repo>/<path>`` (the file of that repository at the commit named; fill DIR
with ``git show <commit>:<path>`` from a clone), and writes ``maps/corpus/<name>.png`` +
``<name>.yaml`` (a ROS map_server pair), ``maps/corpus/corpus.yaml`` (the index) and the
corpus section of ``maps/README.md``. Changes to a source, all recorded in the index:

- every map is cropped to its known cells (free or occupied) plus :data:`MARGIN` unknown
  cells, the origin moved to match, and stored as an 8-bit PNG (PGM sources too);
- a map bigger than :data:`MAX_CELLS` is downsampled by an integer factor: a block is
  occupied if any of its cells is (so no wall vanishes), free if at least half of its cells
  are free and none occupied, unknown otherwise;
- an Open-RMF ``.building.yaml`` level is rasterised: its floor polygons free, its walls
  :data:`WALL_M` thick, everything else unknown (doors are the gaps between walls).

Then each map is loaded back with the project's loader and a base and :data:`TEAM` robot
starts are chosen near a hint (in the main free region: the largest 4-connected one, each
point at least ``MIN_CLEARANCE`` cells from any obstacle cell, starts at least
:data:`SPACING` cells apart; ``tools/corpus.py`` checks them again).
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from numpy.typing import NDArray
from PIL import Image, ImageDraw
from scipy import ndimage

ROOT = Path(__file__).resolve().parent.parent
CORPUS = ROOT / "maps" / "corpus"
MARGIN = 3  # unknown cells kept around the known area after cropping
MAX_CELLS = 700_000
WALL_M = 0.15  # wall thickness (metres) of a rasterised building.yaml level
TEAM = 8
SPACING = 5.0  # cells between two robot starts
MIN_CLEARANCE = 4.0  # cells from a start cell's boundary to the nearest obstacle cell
OCCUPIED, UNKNOWN, FREE = 0, 205, 254  # trinary pixel values written
FREE_THRESH = 0.196  # map_server's default: 205 (p = 0.196078) reads unknown
Grey = NDArray[np.uint8]
Codes = NDArray[np.int8]  # 0 occupied, 1 unknown, 2 free
Cell = tuple[int, int]  # (x = column, y = row)


@dataclass(frozen=True)
class Source:
    """One corpus map: where it comes from, how it is changed, where robots start."""

    name: str
    kind: str
    what: str
    repo: str
    commit: str
    path: str
    licence: str
    hint: Cell  # near where the base goes, in output cells
    level: str | None = None  # building.yaml level to rasterise
    resolution: float | None = None  # for an image without a map YAML (metres per cell)
    note: str = ""


@dataclass
class Raw:
    """A source map as read: grey pixels and its map_server settings."""

    grey: Grey
    resolution: float
    origin: tuple[float, float, float]
    settings: dict[str, Any] = field(default_factory=dict)  # negate, thresholds, mode
    rasterised: bool = False
    image: str = ""  # the source image's file name


AWS_MIT0 = "MIT-0 (LICENSE file; package.xml says Apache 2.0)"
SOURCES = (
    Source(
        "aws_hospital", "hospital",
        "AWS RoboMaker hospital world (Gazebo), mapped with SLAM: wards, patient rooms, "
        "lobby with a curved reception, corridors",
        "quasi-robotics/aws-robomaker-hospital-world", "a854cdfe0571a499d470c328da2bc407a15117e3",
        "maps/hospital.yaml", AWS_MIT0 + "; the map was added in this fork", (260, 90),
    ),
    Source(
        "rmf_hotel_l2", "hotel",
        "Open-RMF demo hotel, level 2: a corridor between 15 guest rooms, lift lobby",
        "open-rmf/rmf_demos", "e1af33e0e8619a9417bf1d23c4c05246ea1d3802",
        "rmf_demos_maps/maps/hotel/hotel.building.yaml", "Apache-2.0 (LICENSE, package.xml)",
        (300, 505), level="L2",
    ),
    Source(
        "ipa_office", "office",
        "Fraunhofer IPA office floor (real SLAM map, 2014): atrium and radiating corridors",
        "ipa320/cob_environments", "dc174b7d654db8cb754f37a2e2b879d67edba0a4",
        "cob_default_env_config/envs/ipa-office/map.yaml",
        "Apache-2.0 (package.xml at this commit)", (350, 320),
    ),
    Source(
        "rmf_office_scan", "office",
        "Open-RMF demo office: the laser scan it is aligned with, desks and meeting rooms",
        "open-rmf/rmf_demos", "e1af33e0e8619a9417bf1d23c4c05246ea1d3802",
        "rmf_demos_maps/maps/office/office_scan.png", "Apache-2.0 (LICENSE, package.xml)",
        (150, 300), resolution=0.0506424,
        note="resolution from the scan layer of office.building.yaml; no origin given",
    ),
    Source(
        "mit_stata_basement", "corridors",
        "MIT Stata Center basement (real SLAM map): a loop of long corridors",
        "mit-racecar/racecar_simulator", "326b258ada9e54cfa142a2f1a0b27c540a408367",
        "maps/stata_basement.yaml", "MIT (package.xml; the repository has no LICENSE file)",
        (100, 40),
    ),
    Source(
        "aws_small_warehouse", "warehouse",
        "AWS RoboMaker small warehouse (Gazebo), mapped with SLAM: shelf rows, offices",
        "aws-robotics/aws-robomaker-small-warehouse-world",
        "3c23a698bf0b4e366ddf8b084af507c519bd3483", "maps/005/map.yaml", AWS_MIT0, (140, 380),
    ),
    Source(
        "nav2_warehouse", "warehouse",
        "Nav2 warehouse world (Gazebo), mapped with SLAM: long racks, loading area",
        "ros-navigation/navigation2", "a3a97043ee93d92fe8d70ec56d183933169beb1c",
        "nav2_bringup/maps/warehouse.yaml", "Apache-2.0 (nav2_bringup package.xml)", (250, 780),
    ),
    Source(
        "nav2_depot", "depot",
        "Nav2 depot world (Gazebo), mapped with SLAM: open hall, pillars, pallet stacks",
        "ros-navigation/navigation2", "a3a97043ee93d92fe8d70ec56d183933169beb1c",
        "nav2_bringup/maps/depot.yaml", "Apache-2.0 (nav2_bringup package.xml)", (40, 150),
    ),
    Source(
        "aws_bookstore", "retail",
        "AWS RoboMaker bookstore (Gazebo), mapped with SLAM: shelves, tables, counter",
        "aws-robotics/aws-robomaker-bookstore-world", "ed542eb41809d5c5f1c67f32d4ba24e0e90886b3",
        "maps/turtlebot3_waffle_pi/map.yaml", AWS_MIT0, (100, 250),
    ),
    Source(
        "aws_small_house", "house",
        "AWS RoboMaker small house (Gazebo), mapped with SLAM: living room, kitchen, bedrooms",
        "aws-robotics/aws-robomaker-small-house-world", "dd44be6205b2e6577bf641300dacc1699cb2ca81",
        "maps/turtlebot3_waffle_pi/map.yaml", AWS_MIT0, (200, 150),
    ),
    Source(
        "ipa_apartment", "apartment",
        "Fraunhofer IPA test apartment: living room, kitchen, bedroom, hall",
        "ipa320/cob_environments", "72ae32d85bef0fde67714ee90bc00fdf33fd8fbc",
        "cob_default_env_config/envs/ipa-apartment/map.yaml", "Apache-2.0 (LICENSE, package.xml)",
        (150, 400),
    ),
    Source(
        "willow_garage", "office",
        "Willow Garage office (real SLAM map, 2010-02-18): corridors round two blocks of "
        "offices, labs, an open hall; kept aside for checking (issue 28), never tuned on",
        "turtlebot/turtlebot_apps", "4bbafc7bfdfc5888ba03b52611bdb56d86b22967",
        "turtlebot_navigation/maps/willow-2010-02-18-0.10.yaml",
        "BSD (turtlebot_navigation package.xml)", (190, 390),
    ),
)  # fmt: skip


def classify(grey: Grey, settings: dict[str, Any]) -> Codes:
    """ROS map_server trinary reading: 0 occupied, 1 unknown, 2 free (as the loader reads)."""
    p = grey / 255.0 if settings.get("negate", 0) else (255.0 - grey) / 255.0
    codes = np.ones(grey.shape, dtype=np.int8)
    codes[p > float(settings.get("occupied_thresh", 0.65))] = 0
    codes[p < float(settings.get("free_thresh", FREE_THRESH))] = 2
    return codes


def read_grey(path: Path) -> Grey:
    """An image's luminance (transparent pixels on white)."""
    with Image.open(path) as opened:
        img: Image.Image = opened
        if img.has_transparency_data:
            rgba = img.convert("RGBA")
            img = Image.alpha_composite(Image.new("RGBA", rgba.size, (255,) * 4), rgba)
        grey: Grey = np.array(img.convert("L"), dtype=np.uint8)
    return grey


def read_ros(path: Path) -> Raw:
    """A map_server YAML and its image."""
    meta = yaml.safe_load(path.read_text(encoding="utf-8"))
    keys = ("negate", "occupied_thresh", "free_thresh", "mode")
    settings = {k: meta[k] for k in keys if k in meta}
    x, y, *yaw = (float(v) for v in meta["origin"])
    grey = read_grey(path.parent / meta["image"])
    origin = (x, y, yaw[0] if yaw else 0.0)
    return Raw(grey, float(meta["resolution"]), origin, settings, image=str(meta["image"]))


def rasterise(path: Path, level: str, resolution: float = 0.05) -> Raw:
    """One level of an Open-RMF building.yaml: floors free, walls occupied, rest unknown.

    Drawing pixels (u, v) are ``scale`` metres apart (the level's measurement); world
    x = u * scale, y = -v * scale as the RMF tools place them.
    """
    data = yaml.safe_load(path.read_text(encoding="utf-8"))["levels"][level]
    points = [(float(v[0]), float(v[1])) for v in data["vertices"]]
    first, second, params = data["measurements"][0]
    scale = float(params["distance"][1]) / math.dist(points[first], points[second])
    k = scale / resolution
    width = math.ceil(max(p[0] for p in points) * k) + 1
    height = math.ceil(max(p[1] for p in points) * k) + 1
    img = Image.new("L", (width, height), UNKNOWN)
    draw = ImageDraw.Draw(img)
    for floor in data["floors"]:
        draw.polygon([(points[i][0] * k, points[i][1] * k) for i in floor["vertices"]], FREE)
    thick = max(1, round(WALL_M / resolution))
    for a, b, _ in data["walls"]:
        ends = [(points[a][0] * k, points[a][1] * k), (points[b][0] * k, points[b][1] * k)]
        draw.line(ends, fill=OCCUPIED, width=thick)
    grey = np.asarray(img, dtype=np.uint8).copy()
    return Raw(grey, resolution, (0.0, -height * resolution, 0.0), {}, rasterised=True)


def read_source(src: Path, source: Source) -> Raw:
    """The source map of ``source`` under ``src``."""
    path = src / source.repo / source.path
    if source.level is not None:
        return rasterise(path, source.level)
    if source.resolution is not None:
        return Raw(read_grey(path), source.resolution, (0.0, 0.0, 0.0), image=path.name)
    return read_ros(path)


def shifted_origin(raw: Raw, left: int, rows_below: int) -> list[float]:
    """The origin (lower-left pixel) of a window of ``raw`` whose first column is ``left``
    and whose last row has ``rows_below`` source rows under it (negative when padded):
    the corner moves by that many cells along the map's rotated axes."""
    x, y, yaw = raw.origin
    dx, dy = left * raw.resolution, rows_below * raw.resolution
    c, s = math.cos(yaw), math.sin(yaw)
    return [round(x + c * dx - s * dy, 6), round(y + s * dx + c * dy, 6), yaw]


def crop_window(codes: Codes, factor: int) -> tuple[int, int, int, int]:
    """(top, left, bottom, right) of the known cells plus :data:`MARGIN`, grown so both
    sides are multiples of ``factor`` (it may reach past the map: padded with unknown)."""
    rows, cols = np.nonzero(codes != 1)
    top, left = int(rows.min()) - MARGIN, int(cols.min()) - MARGIN
    bottom, right = int(rows.max()) + 1 + MARGIN, int(cols.max()) + 1 + MARGIN
    bottom += -(bottom - top) % factor
    right += -(right - left) % factor
    return top, left, bottom, right


def window(grey: Grey, box: tuple[int, int, int, int]) -> Grey:
    """``grey`` cut to ``box``, padded with the unknown value where it reaches outside."""
    top, left, bottom, right = box
    pad = (
        (max(0, -top), max(0, bottom - grey.shape[0])),
        (max(0, -left), max(0, right - grey.shape[1])),
    )
    padded = np.pad(grey, pad, constant_values=UNKNOWN)
    return padded[top + pad[0][0] : bottom + pad[0][0], left + pad[1][0] : right + pad[1][0]]


def pool(codes: Codes, factor: int) -> Grey:
    """Downsample by ``factor``: occupied if any cell is, free if half are free, else unknown."""
    rows, cols = codes.shape[0] // factor, codes.shape[1] // factor
    blocks = codes.reshape(rows, factor, cols, factor).transpose(0, 2, 1, 3)
    occupied = (blocks == 0).any(axis=(2, 3))
    free = (blocks == 2).sum(axis=(2, 3)) * 2 >= factor * factor
    out = np.full((rows, cols), UNKNOWN, dtype=np.uint8)
    out[free] = FREE
    out[occupied] = OCCUPIED
    return out


@dataclass(frozen=True)
class Converted:
    """A corpus map ready to write, and what was done to it."""

    grey: Grey
    meta: dict[str, Any]
    changes: list[str]


def unknown_stays_unknown(raw: Raw) -> list[str]:
    """Lower a free_thresh that reads map_saver's unknown value (205) as free to
    :data:`FREE_THRESH` (the map_server default); the change made, if any."""
    given = float(raw.settings.get("free_thresh", FREE_THRESH))
    if given <= FREE_THRESH:
        return []
    raw.settings["free_thresh"] = FREE_THRESH
    return [f"free_thresh {given} -> {FREE_THRESH}: at {given} the unknown value 205 reads free"]


def convert(raw: Raw, source: Source) -> Converted:
    """Crop (and downsample or rasterise) ``raw``; the map YAML and the list of changes."""
    fixed = unknown_stays_unknown(raw)
    codes = classify(raw.grey, raw.settings)
    factor = max(1, math.ceil(math.sqrt(_known_box_cells(codes) / MAX_CELLS)))
    box = crop_window(codes, factor)
    _, left, bottom, _ = box
    grey = window(raw.grey, box)
    origin = shifted_origin(raw, left, raw.grey.shape[0] - bottom)
    changes = _describe(raw, source, grey.shape) + fixed
    settings = dict(raw.settings)
    if factor > 1:
        grey = pool(classify(grey, raw.settings), factor)
        settings = {"negate": 0, "occupied_thresh": 0.65, "free_thresh": FREE_THRESH}
        res = f"{raw.resolution:g} -> {raw.resolution * factor:g} m/cell"
        changes.append(f"downsampled {factor}x: {res}, obstacles max-pooled")
    meta = {
        "image": f"{source.name}.png",
        "resolution": round(raw.resolution * factor, 7),
        "origin": origin,
        "negate": int(settings.get("negate", 0)),
        "occupied_thresh": float(settings.get("occupied_thresh", 0.65)),
        "free_thresh": float(settings.get("free_thresh", FREE_THRESH)),
        "mode": "trinary",
    }
    return Converted(np.ascontiguousarray(grey), meta, changes)


def _known_box_cells(codes: Codes) -> int:
    """Cells of the known area's bounding box with its margin."""
    top, left, bottom, right = crop_window(codes, 1)
    return (bottom - top) * (right - left)


def _describe(raw: Raw, source: Source, shape: tuple[int, ...]) -> list[str]:
    """The changes every map gets: the rasterisation, the crop, the PNG."""
    size = f"{raw.grey.shape[1]}x{raw.grey.shape[0]} -> {shape[1]}x{shape[0]} cells"
    crop = f"cropped to the known area + {MARGIN} cells ({size}), origin moved to match"
    if raw.rasterised:
        rule = f"floors free, walls {WALL_M} m thick, the rest unknown"
        return [f"level {source.level} rasterised at {raw.resolution} m/cell ({rule})", crop]
    if raw.image.lower().endswith(".png"):
        return [crop]
    return [crop, "stored as PNG (pixel values unchanged)"]


def clearance(occupied: NDArray[np.bool_]) -> NDArray[np.float64]:
    """Distance from each cell's boundary to the nearest obstacle cell (outside = obstacle)."""
    padded = np.pad(~occupied, 1, constant_values=False)
    return np.asarray(ndimage.distance_transform_edt(padded), dtype=np.float64)[1:-1, 1:-1] - 0.5


def main_region(occupied: NDArray[np.bool_]) -> NDArray[np.bool_]:
    """The largest 4-connected free region."""
    labels, count = ndimage.label(~occupied)
    if count == 0:
        raise ValueError("the map has no free cell")
    sizes = np.bincount(labels.ravel())
    sizes[0] = 0
    return np.asarray(labels == int(np.argmax(sizes)))


def choose_points(occupied: NDArray[np.bool_], hint: Cell, count: int) -> list[Cell]:
    """The base then ``count`` starts: the allowed cells nearest ``hint``, starts at least
    :data:`SPACING` apart (allowed: in the main region, :data:`MIN_CLEARANCE` from walls)."""
    allowed = main_region(occupied) & (clearance(occupied) >= MIN_CLEARANCE)
    rows, cols = np.nonzero(allowed)
    order = np.argsort((cols - hint[0]) ** 2 + (rows - hint[1]) ** 2, kind="stable")
    chosen: list[Cell] = []
    for k in order:
        cell = (int(cols[k]), int(rows[k]))
        if all(math.dist(cell, c) >= SPACING for c in chosen):
            chosen.append(cell)
            if len(chosen) == count + 1:
                return chosen
    raise ValueError(f"only {len(chosen)} points fit near {hint}")


def load_back(yaml_path: Path) -> NDArray[np.bool_]:
    """The occupancy grid of a written map, read by the project's loader."""
    sys.path.insert(0, str(ROOT))
    from mresim_phys.scenario.readers import load_ros_map

    return load_ros_map(yaml_path).occupied


def write_map(out: Path, source: Source, converted: Converted) -> Path:
    """Write the PNG and its map YAML; the YAML's path."""
    out.mkdir(parents=True, exist_ok=True)
    Image.fromarray(converted.grey).save(out / f"{source.name}.png", optimize=True)
    path = out / f"{source.name}.yaml"
    path.write_text(yaml.safe_dump(converted.meta, sort_keys=False), encoding="utf-8")
    return path


def index_entry(source: Source, converted: Converted, points: list[Cell]) -> dict[str, Any]:
    """The corpus.yaml entry of one map."""
    return {
        "name": source.name,
        "file": f"{source.name}.yaml",
        "kind": source.kind,
        "what": source.what,
        "source": f"https://github.com/{source.repo}/blob/{source.commit}/{source.path}",
        "licence": source.licence,
        "modified": True,
        "changes": [*converted.changes, *([source.note] if source.note else [])],
        "resolution": converted.meta["resolution"],
        "base": list(points[0]),
        "starts": [list(p) for p in points[1:]],
    }


def import_all(src: Path, out: Path, names: set[str] | None = None) -> list[dict[str, Any]]:
    """Convert every source (or those named), write the maps; the index entries."""
    entries = []
    for source in SOURCES:
        if names and source.name not in names:
            continue
        converted = convert(read_source(src, source), source)
        occupied = load_back(write_map(out, source, converted))
        points = choose_points(occupied, source.hint, TEAM)
        entries.append(index_entry(source, converted, points))
        print(f"{source.name:20s} {occupied.shape[1]}x{occupied.shape[0]} base {points[0]}")
    return entries


INDEX_HEADER = """\
# The corpus of real building maps: written by `python tools/corpus_import.py`; do not edit
# by hand. Positions are cells (x = column, y = row); place a robot at the cell centre
# (x + 0.5, y + 0.5). maps/README.md describes the corpus.
"""


class IndexDumper(yaml.SafeDumper):
    """YAML dumper writing points (lists of numbers) on one line: ``[x, y]``."""


def _flow_points(dumper: yaml.SafeDumper, data: list[Any]) -> yaml.Node:
    flow = all(isinstance(v, int | float) for v in data)
    return dumper.represent_sequence("tag:yaml.org,2002:seq", data, flow_style=flow)


IndexDumper.add_representer(list, _flow_points)


def write_index(out: Path, entries: list[dict[str, Any]]) -> None:
    """Write ``corpus.yaml`` (entries of maps not re-imported are kept)."""
    path = out / "corpus.yaml"
    old = yaml.safe_load(path.read_text(encoding="utf-8"))["maps"] if path.exists() else []
    fresh = {e["name"] for e in entries}
    order = [s.name for s in SOURCES]
    merged = [e for e in old if e["name"] not in fresh and e["name"] in order] + entries
    merged.sort(key=lambda e: order.index(e["name"]))
    body = yaml.dump({"maps": merged}, Dumper=IndexDumper, sort_keys=False, width=100)
    path.write_text(INDEX_HEADER + body, encoding="utf-8")


README_HEAD = "## Corpus of real building maps"
README_TEXT = """{head}

`maps/corpus/` holds {count} maps of real buildings taken from public ROS packages and SLAM
maps under permissive licences, as ROS map_server pairs (`name.yaml` + `name.png`, the
source's resolution and origin kept), with the index `maps/corpus/corpus.yaml` (kind,
source, licence, every change made, a base and {team} robot starts per map). Written by
`python tools/corpus_import.py --src DIR` from the source files (DIR/owner/repo/path, at the
commit in each source link); `tools/make_maps.py` rewrites this README without this
section: run `tools/corpus_import.py` after it. `python tools/corpus.py check` checks the
index, `python tools/corpus.py run ...` runs teams on the maps (see its docstring).

| map | cells (cols x rows) | metres | free cells | reachable | kind | source | licence |
|---|---|---|---|---|---|---|---|
{table}

Changes, recorded per map in the index: every map is cropped to its known cells plus
{margin} unknown cells (origin moved to match) and stored as an 8-bit PNG; a map over
{max_cells:,} cells is downsampled by an integer factor, obstacles max-pooled so that no wall
vanishes ({pooled}); the hotel level is rasterised from the
Open-RMF building file (floor polygons free, walls {wall} m thick, the rest unknown; its
doors are the gaps between walls); two nav2-style YAMLs with `free_thresh: 0.25`, which
reads the unknown value 205 as free, get 0.196. Unknown cells count as obstacles, so SLAM
rays that leak out of a building add a few unreachable specks, not explorable area.
"Reachable" is the free region of the starts (the explored-area denominator). Maps of
Gazebo worlds (AWS RoboMaker, Nav2) are SLAM maps of simulated buildings; `ipa_office` and
`mit_stata_basement` are SLAM maps of real floors, `rmf_office_scan` the laser scan the
Open-RMF demo office is aligned with, and `rmf_hotel_l2` a drawn floor plan.

Starts: the base is the cell nearest a hand-picked hint (an entrance, a lobby or a corridor)
among the cells of the largest free region at least {clearance} cells from any obstacle
cell; the {team} robot starts are the next nearest such cells at least {spacing:g} cells
apart (a 3 x 3 block around the base where there is room). `tools/corpus_import.py`
chooses them and `tools/corpus.py check` (and `tests/test_corpus.py`) checks that each is
free, at least {clearance} cells from any wall and in the base's connected free region.
"""


def readme_row(entry: dict[str, Any], out: Path) -> str:
    """The README table row of one index entry (figures from the written map)."""
    occupied = load_back(out / entry["file"])
    rows, cols = occupied.shape
    res = float(entry["resolution"])
    free = int((~occupied).sum())
    x, y = entry["base"]
    labels, _ = ndimage.label(~occupied)
    reachable = int((labels == labels[y, x]).sum())
    repo = "/".join(entry["source"].split("/")[3:5])
    cells = [
        entry["name"], f"{cols} x {rows}", f"{cols * res:.0f} x {rows * res:.0f}", f"{free:,}",
        f"{reachable:,}", entry["kind"], f"[{repo}]({entry['source']})", entry["licence"],
    ]  # fmt: skip
    return "| " + " | ".join(cells) + " |"


def write_readme(path: Path, out: Path) -> None:
    """Replace (or add) the corpus section at the end of ``path``."""
    entries = yaml.safe_load((out / "corpus.yaml").read_text(encoding="utf-8"))["maps"]
    section = README_TEXT.format(
        head=README_HEAD, count=len(entries), team=TEAM, margin=MARGIN, max_cells=MAX_CELLS,
        wall=WALL_M, clearance=int(MIN_CLEARANCE), spacing=SPACING,
        table="\n".join(readme_row(e, out) for e in entries),
        pooled="; ".join(
            f"`{e['name']}` {c.removeprefix('downsampled ').split(', ')[0]}"
            for e in entries
            for c in e["changes"]
            if c.startswith("downsampled")
        ),
    )  # fmt: skip
    text = path.read_text(encoding="utf-8")
    if README_HEAD in text:
        text = text[: text.index(README_HEAD)].rstrip("\n") + "\n"
    path.write_text(text + "\n" + section, encoding="utf-8")


def main(argv: list[str] | None = None) -> int:
    """Import the sources found under ``--src`` into ``--out``."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--src", type=Path, required=True, help="DIR/<owner>/<repo>/<path>")
    parser.add_argument("--out", type=Path, default=CORPUS, help="output folder")
    parser.add_argument("--readme", type=Path, default=ROOT / "maps" / "README.md")
    parser.add_argument("names", nargs="*", help="maps to import (default: all)")
    args = parser.parse_args(argv)
    entries = import_all(args.src, args.out, set(args.names) or None)
    write_index(args.out, entries)
    write_readme(args.readme, args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
