"""Phase 0 data export (offline): a corpus map as the original MRESim reads a map.

The original Java MRESim loads an 800 x 600 image, one pixel a cell, and reads a pixel as
free when its first band is not 0. ``python tools/original_png.py NAME --original TREE``
writes the corpus map ``NAME`` (``maps/corpus/corpus.yaml``) as such an image,
``TREE/environments/corpus/NAME.png`` (outside this repository: the original's tree), and
its team file ``tools/original_teams/NAME_8robots`` (the corpus base and 8 starts, the
original's settings as in the other files there: laser 200, radio 200, battery 1000), so
that ``tools/compare_original.py --case environments/corpus/NAME.png=
tools/original_teams/NAME_8robots`` runs both simulators on it.

The image: every cell our loader reads as free is white, every other cell (wall, unknown)
black. A map larger than 800 x 600 loses, edge by edge, the outer row or column holding
the fewest free cells until it fits (on a SLAM map those are the tips of laser fans); the
count of free cells lost is printed. The map is centred on the black canvas.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from PIL import Image

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))

from corpus import CorpusMap, load_index, select  # noqa: E402  (a sibling script's module)

WIDTH, HEIGHT = 800, 600  # the original's world
TEAM_LINE = "{id} {name} {x} {y} 0.0 {laser} 200 1000 {role} 1 1"
Free = NDArray[np.bool_]


def free_cells(entry: CorpusMap) -> Free:
    """The cells our loader reads as free (unknown counts as obstacle)."""
    sys.path.insert(0, str(ROOT))
    from mresim_phys.scenario.readers import load_ros_map

    return np.asarray(~load_ros_map(entry.file).occupied)


def trim(free: Free, height: int = HEIGHT, width: int = WIDTH) -> tuple[Free, int, int]:
    """``free`` cut to at most ``height`` x ``width``: the outer row or column with the
    fewest free cells goes first. The cut grid and the rows, columns cut at the top, left."""
    top, left = 0, 0
    while free.shape[0] > height or free.shape[1] > width:
        sides = []
        if free.shape[0] > height:
            sides += [(int(free[0].sum()), "top"), (int(free[-1].sum()), "bottom")]
        if free.shape[1] > width:
            sides += [(int(free[:, 0].sum()), "left"), (int(free[:, -1].sum()), "right")]
        side = min(sides)[1]
        if side == "top":
            free, top = free[1:], top + 1
        elif side == "bottom":
            free = free[:-1]
        elif side == "left":
            free, left = free[:, 1:], left + 1
        else:
            free = free[:, :-1]
    return free, top, left


def canvas(free: Free) -> tuple[NDArray[np.uint8], int, int]:
    """The 800 x 600 RGB image with ``free`` centred; its column and row offsets."""
    x0, y0 = (WIDTH - free.shape[1]) // 2, (HEIGHT - free.shape[0]) // 2
    image = np.zeros((HEIGHT, WIDTH, 3), dtype=np.uint8)
    image[y0 : y0 + free.shape[0], x0 : x0 + free.shape[1]][free] = 255
    return image, x0, y0


def team_text(entry: CorpusMap, dx: int, dy: int) -> str:
    """The original's team file: the base, then the 8 starts, moved by (dx, dy) pixels."""
    line = TEAM_LINE.format
    x, y = entry.base
    lines = [line(id=1, name="BaseStation", x=x + dx, y=y + dy, laser=0, role="BaseStation")]
    for k, (x, y) in enumerate(entry.starts):
        name = chr(ord("A") + k)
        lines.append(line(id=k + 2, name=name, x=x + dx, y=y + dy, laser=200, role="Explorer"))
    return "\n".join(lines) + "\n"


def export(entry: CorpusMap, original: Path, teams: Path) -> tuple[Path, Path, int]:
    """Write the image and the team file of ``entry``; their paths and free cells lost."""
    free = free_cells(entry)
    cut, top, left = trim(free)
    image, x0, y0 = canvas(cut)
    for x, y in (entry.base, *entry.starts):
        if not image[y - top + y0, x - left + x0, 0]:
            raise ValueError(f"{entry.name}: the start ({x}, {y}) was cut off or is not free")
    png = original / "environments" / "corpus" / f"{entry.name}.png"
    png.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(image).save(png)
    team = teams / f"{entry.name}_{len(entry.starts)}robots"
    team.write_text(team_text(entry, x0 - left, y0 - top), encoding="utf-8")
    return png, team, int(free.sum() - cut.sum())


def main(argv: list[str] | None = None) -> int:
    """Export the corpus maps named on the command line."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("names", help="corpus maps, comma-separated")
    parser.add_argument("--original", type=Path, required=True, help="the original's tree")
    parser.add_argument("--teams", type=Path, default=HERE / "original_teams")
    args = parser.parse_args(argv)
    sys.path.insert(0, str(ROOT))
    from mresim_phys.errors import MresimError

    try:
        for entry in select(load_index(), args.names):
            png, team, lost = export(entry, args.original, args.teams)
            print(f"{entry.name}: {png} ({lost} free cells cut), {team}")
    except (ValueError, OSError, MresimError) as exc:  # a bad index or map, an unwritable tree
        print(f"original_png: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
