"""Views (phase 8), raster stage: the label grid of a snapshot, in a few numba passes.

A label is ``class + 6 * tint`` per cell. Classes: 0 unexplored, 1 team-known, 2 known at
base, 3 wall, 4 skeleton, 5 frontier (the larger wins). Tints: 0 none, ``1 + i`` robot
``i``'s free space, ``1 + n + i`` its safe space, ``n`` palette colours (the larger wins:
later robots over earlier ones, safe space over free space). ``render.Renderer`` colours
labels with one lookup table (``render.style.Style.lut``).

Per robot, the first pass (:func:`known_box`) finds the bounding box of its known cells;
the second (:func:`mark_robot`) runs over that box (+1) only, while the belief is still in
cache, and fuses the team-known class, the free and safe tints and the frontier test (a
FREE cell with an UNKNOWN cell among its 8 neighbours not hidden behind a wall corner, as
``frontiers.frontier_mask``). The
frontier test fills one row buffer per row ("an UNKNOWN cell above, at or below, in this
column"), so every inner loop is branch-free over contiguous row slices and vectorises. A
last pass (:func:`finish_labels`) adds the known-at-base and wall classes and the tints;
then :func:`mark_world` puts the changing world's solid labels (rubble, closed doors,
moving obstacles; ``style.RUBBLE`` ...) over them, and :func:`shade_terrain` tints slow
ground brown (the ``terrain`` layer) and :func:`shade_prior` tints blue where a prior map
holds walls the truth does not have (the ``prior`` layer); :func:`shade_lost` tints crimson
the cells lost at robot failures (the ``lost_knowledge`` layer).
These replaced ~20 numpy/cv2 calls per robot (bounding rectangle, masks, products and
maxima, a dilation) that swept the same cells again and again: on an 8-robot office frame
(800x600, ``benchmarks/bench_render.py``) the label grid went from ~5.2 to ~1.0-1.3 ms.

Typical use: ``LabelGrids((rows, cols)).labels(snapshot, layers, palette_size)``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import cv2
import numpy as np
from numba import njit
from numpy.typing import NDArray

from mresim_phys.knowledge.frontiers import sees_unknown
from mresim_phys.render.layers import LayerSpec
from mresim_phys.render.style import (
    AT_BASE,
    CLASSES,
    DOOR,
    FRONTIER,
    OBSTACLE,
    RUBBLE,
    SKELETON,
    TEAM_KNOWN,
    WALL,
    Style,
)
from mresim_phys.types import FREE, OCCUPIED, UNKNOWN, BeliefGrid, BoolGrid

if TYPE_CHECKING:
    from mresim_phys.snapshot import GroundLayer, Snapshot


@njit(cache=True, nogil=True)
def known_box(belief: BeliefGrid) -> tuple[int, int, int, int]:
    """Bounding box (row0, row1, col0, col1; half-open) of the non-zero cells of ``belief``,
    or (0, 0, 0, 0) if there are none."""
    rows, cols = belief.shape
    seen = np.zeros(cols, np.uint8)
    r0, r1 = -1, -1
    for r in range(rows):
        row = belief[r]
        known = np.uint8(0)
        for c in range(cols):
            known = np.uint8(known | row[c])
        if known:
            r0, r1 = r if r0 < 0 else r0, r + 1
            for c in range(cols):
                seen[c] = np.uint8(seen[c] | row[c])
    if r0 < 0:
        return 0, 0, 0, 0
    c0, c1 = 0, cols
    while seen[c0] == 0:
        c0 += 1
    while seen[c1 - 1] == 0:
        c1 -= 1
    return r0, r1, c0, c1


@njit(cache=True, nogil=True)
def mark_robot(
    belief: BeliefGrid,
    safe: BoolGrid,
    label: BeliefGrid,
    tint: BeliefGrid,
    box: tuple[int, int, int, int],
    values: tuple[int, int, int, int],
) -> None:
    """Within ``box``, raise ``tint`` to ``values[0]`` on FREE cells and to ``values[1]`` on
    safe cells, and ``label`` to ``values[2]`` on frontier cells and to ``values[3]`` on
    FREE cells (team-known); a value of 0 leaves its layer off.

    Frontier cells are FREE cells with an UNKNOWN cell among their 8 neighbours in the grid:
    per row, ``near[1 + k]`` flags an UNKNOWN cell in column c0 + k of the rows above, at
    and below, and a cell is a frontier if ``near`` flags it or a column next to it, and
    :func:`~mresim_phys.knowledge.frontiers.sees_unknown` (no wall corner hides them all).
    """
    r0, r1, c0, c1 = box
    rows, cols = belief.shape
    free_tint, safe_tint = np.uint8(values[0]), np.uint8(values[1])
    frontier, known = np.uint8(values[2]), np.uint8(values[3])
    w = c1 - c0
    lo, hi = max(c0 - 1, 0), min(c1 + 1, cols)  # columns whose cells can be neighbours
    near = np.zeros(w + 2, np.uint8)  # stays 0 at columns outside the grid
    inside = near[lo - c0 + 1 : hi - c0 + 1]
    outside = np.ones(cols, np.uint8)  # the rows outside the grid are not unknown
    for r in range(r0, r1):
        if frontier:
            up = belief[r - 1, lo:hi] if r > 0 else outside[lo:hi]
            mid = belief[r, lo:hi]
            down = belief[r + 1, lo:hi] if r + 1 < rows else outside[lo:hi]
            for k in range(hi - lo):
                unknown = np.uint8(up[k] == UNKNOWN) | np.uint8(mid[k] == UNKNOWN)
                inside[k] = np.uint8(unknown | np.uint8(down[k] == UNKNOWN))
        cells, safe_row = belief[r, c0:c1], safe[r, c0:c1]
        label_row, tint_row = label[r, c0:c1], tint[r, c0:c1]
        for k in range(w):
            free = np.uint8(cells[k] == FREE)
            raised = max(tint_row[k], np.uint8(free * free_tint))
            tint_row[k] = max(raised, np.uint8(np.uint8(safe_row[k]) * safe_tint))
            edge = np.uint8(np.uint8(near[k] | near[k + 1] | near[k + 2]) & free)
            if edge and not sees_unknown(belief, r, c0 + k):  # hidden behind a wall corner
                edge = np.uint8(0)
            marked = max(np.uint8(edge * frontier), np.uint8(free * known))
            label_row[k] = max(label_row[k], marked)


@njit(cache=True, nogil=True)
def finish_labels(
    label: BeliefGrid, tint: BeliefGrid, base: BeliefGrid, truth: BoolGrid, on: tuple[int, int]
) -> None:
    """``label`` = the largest of ``label`` (robot marks), known at base and wall, each as
    its ``on`` value (0 = layer off), plus ``CLASSES * tint``."""
    base_on, wall_on = np.uint8(on[0]), np.uint8(on[1])
    for r in range(label.shape[0]):
        out, add, at_base, wall = label[r], tint[r], base[r], truth[r]
        for c in range(label.shape[1]):
            value = max(out[c], np.uint8(np.uint8(at_base[c] == FREE) * base_on))
            value = max(value, np.uint8(np.uint8(wall[c]) * wall_on))
            out[c] = np.uint8(value + np.uint8(CLASSES) * add[c])


@njit(cache=True, nogil=True)
def colour_labels(label: np.ndarray, table: np.ndarray, image: np.ndarray) -> None:
    """``image[r, c]`` = the colour ``table[label[r, c]]`` (uint32 0xRRGGBB as BGR bytes);
    cells of ``image`` beyond the label grid (padding) take ``table[0]``."""
    rows, cols = label.shape
    for r in range(image.shape[0]):
        out = image[r]
        if r < rows:
            cells = label[r]
            for c in range(cols):
                bgr = table[cells[c]]
                out[c, 0], out[c, 1], out[c, 2] = bgr, bgr >> 8, bgr >> 16
        for c in range(cols if r < rows else 0, image.shape[1]):
            out[c, 0], out[c, 1], out[c, 2] = table[0], table[0] >> 8, table[0] >> 16


class LabelGrids:
    """Scratch grids reused by every frame of one map (fresh ones cost page faults)."""

    def __init__(self, shape: tuple[int, int]) -> None:
        self.label, self.tint = (np.empty(shape, dtype=np.uint8) for _ in range(2))

    def labels(self, snapshot: Snapshot, layers: LayerSpec, n: int) -> np.ndarray:
        """The label grid of ``snapshot`` (in a scratch buffer) for ``n`` palette colours.

        Robot by robot, the box pass and the marks over that box run back to back, while
        the robot's belief is still in cache; the map classes come last (all are maxima).
        """
        on = layers.global_layers
        self.label.fill(0)
        self.tint.fill(0)
        for i, robot in enumerate(snapshot.robots):
            mine, belief = layers.for_agent(robot.name), as_cells(robot.belief)
            box = known_box(belief)
            if box[1] > box[0]:
                values = (
                    (1 + i % n) * ("free_space" in mine),
                    (1 + n + i % n) * ("safe_space" in mine),
                    FRONTIER * ("frontiers" in mine),
                    TEAM_KNOWN * ("team_known" in on),
                )
                box = padded_box(box, self.label.shape)
                mark_robot(belief, as_bool(robot.safe), self.label, self.tint, box, values)
            if "skeleton" in mine and robot.skeleton is not None:
                skeleton = as_bool(robot.skeleton).view(np.uint8) * np.uint8(SKELETON)
                np.maximum(self.label, skeleton, out=self.label)
        flags = (AT_BASE * ("known_at_base" in on), WALL * ("walls" in on))
        base, truth = as_cells(snapshot.base.belief), as_bool(snapshot.truth)
        finish_labels(self.label, self.tint, base, truth, flags)
        mark_world(self.label, snapshot, on)
        return self.label


def mark_world(label: np.ndarray, snapshot: Snapshot, on: frozenset[str]) -> None:
    """The changing world's solid labels over every class: rubble, then closed doors, then
    moving obstacles on the map (each when its layer is on; a static run has none)."""
    if "debris" in on and snapshot.rubble is not None:
        np.putmask(label, as_bool(snapshot.rubble), np.uint8(RUBBLE))
    for kind, layer, value in (("door", "doors", DOOR), ("obstacle", "obstacles", OBSTACLE)):
        if layer in on:
            for movable in snapshot.movables:
                if movable.kind == kind and movable.on:
                    mark_cells(label, movable.cells, movable.at, value)


def mark_cells(label: np.ndarray, cells: np.ndarray, at: tuple[int, int], value: int) -> None:
    """``label`` = ``value`` on the True ``cells`` whose top-left cell is ``at`` (clipped)."""
    rows, cols = label.shape
    h, w = cells.shape
    r0, c0 = max(at[0], 0), max(at[1], 0)
    r1, c1 = min(at[0] + h, rows), min(at[1] + w, cols)
    if r0 < r1 and c0 < c1:
        mine = cells[r0 - at[0] : r1 - at[0], c0 - at[1] : c1 - at[1]]
        label[r0:r1, c0:c1][mine] = value


def as_cells(grid: np.ndarray) -> np.ndarray:
    """``grid`` as a C-contiguous uint8 array (no copy when it is one already)."""
    return np.ascontiguousarray(grid, dtype=np.uint8)


def as_bool(grid: np.ndarray) -> np.ndarray:
    """``grid`` as a C-contiguous bool array (no copy when it is one already)."""
    return np.ascontiguousarray(grid, dtype=bool)


def padded_box(box: tuple[int, int, int, int], shape: tuple[int, int]) -> tuple[int, int, int, int]:
    """``box`` grown by one cell on every side, clipped to ``shape``."""
    r0, r1, c0, c1 = box
    return max(r0 - 1, 0), min(r1 + 1, shape[0]), max(c0 - 1, 0), min(c1 + 1, shape[1])


def packed_colours(lut: np.ndarray) -> np.ndarray:
    """A (256, 1, 3) BGR lookup table as 256 uint32 values 0xRRGGBB (for colour_labels)."""
    bgr = lut.reshape(256, 3).astype(np.uint32)
    return bgr[:, 0] | bgr[:, 1] << 8 | bgr[:, 2] << 16


def shade_terrain(
    image: np.ndarray,
    terrain: NDArray[np.float32],
    truth: BoolGrid,
    map_size: tuple[int, int],
    style: Style,
) -> None:
    """Tint the free cells of the coloured frame ``image`` (its map area: ``map_size``
    (width, height) pixels, top left) toward ``style.terrain`` by ``terrain_alpha *
    (1 - factor)``: the slower, the browner; walls and open floor (factor 1) stay. In place."""
    alpha = np.where(truth, np.float32(0), np.float32(style.terrain_alpha) * (1 - terrain))
    tint_cells(image, alpha, style.terrain, map_size)


def shade_ground(
    image: np.ndarray, ground: GroundLayer, truth: BoolGrid, map_size: tuple[int, int], style: Style
) -> None:
    """Tint the free cells of each ground class toward its colour (its legend colour, RGB)
    by ``ground_alpha`` (the ``ground`` layer). In place."""
    free = ~truth
    for value, rgb in enumerate(ground.colours, start=1):
        cells = (ground.grid == value) & free
        alpha = np.float32(style.ground_alpha) * cells.astype(np.float32)
        tint_cells(image, alpha, (rgb[2], rgb[1], rgb[0]), map_size)


def shade_prior(
    image: np.ndarray, prior: NDArray[np.uint8], truth: BoolGrid, map_size: tuple[int, int],
    style: Style,
) -> None:  # fmt: skip
    """Tint the cells that the prior map holds as walls but are free in the truth of this
    step toward ``style.prior`` by ``prior_alpha`` (the ``prior`` layer: where the plan
    the robots were given is out of date, or wrong). In place."""
    ghost = (prior == OCCUPIED) & ~truth
    tint_cells(image, np.float32(style.prior_alpha) * ghost.astype(np.float32), style.prior,
               map_size)  # fmt: skip


def shade_lost(image: np.ndarray, lost: BoolGrid, map_size: tuple[int, int], style: Style) -> None:
    """Tint the cells lost at failures (only a robot that fell silent knew them then)
    toward ``style.lost_knowledge`` by ``lost_alpha`` (the ``lost_knowledge`` layer). In place."""
    tint_cells(image, np.float32(style.lost_alpha) * lost.astype(np.float32),
               style.lost_knowledge, map_size)  # fmt: skip


def shade_ghosts(
    image: np.ndarray, snapshot: Snapshot, layers: LayerSpec, map_size: tuple[int, int],
    style: Style,
) -> None:  # fmt: skip
    """Paint ``style.ghost_wall`` over the ghost walls of the agents that show the
    ``ghost_walls`` layer: cells their maps hold as walls where the truth is free (drift
    smearing a scan, a bump marked where the robot believed it was). In place."""
    shown = [a for a in snapshot.agents if "ghost_walls" in layers.for_agent(a.name)]
    if not shown:
        return
    truth = as_bool(snapshot.truth)
    ghost = np.zeros(truth.shape, dtype=bool)
    for agent in shown:
        ghost |= as_cells(agent.belief) == OCCUPIED
    ghost &= ~truth
    tint_cells(image, ghost.astype(np.float32), style.ghost_wall, map_size)


def shade_hazards(
    image: np.ndarray, hazards: NDArray[np.float32], truth: BoolGrid, map_size: tuple[int, int],
    style: Style,
) -> None:  # fmt: skip
    """Tint the free cells of hazard zones toward ``style.hazard`` by ``hazard_alpha`` (the
    ``hazards`` layer: where each step fails a robot with some probability). In place."""
    zone = (hazards > 0) & ~truth
    tint_cells(image, np.float32(style.hazard_alpha) * zone.astype(np.float32), style.hazard,
               map_size)  # fmt: skip


def tint_cells(
    image: np.ndarray, alpha: NDArray[np.float32], colour: tuple[int, int, int],
    map_size: tuple[int, int],
) -> None:  # fmt: skip
    """Blend the map area of ``image`` toward ``colour`` by a per-cell ``alpha`` (resized
    to ``map_size`` pixels: averaged when shrinking, nearest when growing). In place."""
    if not alpha.any():
        return
    width, height = map_size
    sampling = cv2.INTER_AREA if width < alpha.shape[1] else cv2.INTER_NEAREST
    grown = cv2.resize(alpha.astype(np.float32), (width, height), None, 0, 0, sampling)
    area = image[:height, :width]
    tint = np.asarray(colour, dtype=np.float32)
    shaded = area * (1 - grown[..., None]) + tint * grown[..., None]
    area[...] = np.round(shaded).astype(np.uint8)
