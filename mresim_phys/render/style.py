"""Views (phase 8), style: colours and sizes, and the label classes they colour.

A frame's raster stage (:mod:`~mresim_phys.render.raster`) gives every cell a label
``class + CLASSES * tint``: classes 0 unexplored, 1 team-known, 2 known at base, 3 wall,
4 skeleton, 5 frontier (the larger wins); tints 0 none, ``1 + i`` robot ``i``'s free
space, ``1 + n + i`` its safe space. :meth:`Style.lut` is the lookup table from labels to
BGR colours, and the last three labels are the changing world's solid cells (rubble,
closed doors, moving obstacles; drawn over every class); the vector stage
(:mod:`~mresim_phys.render.draw`) takes its colours and sizes from the same :class:`Style`.

Typical use: ``Style().lut(parse_layers("all"))``.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from mresim_phys.render.layers import LayerSpec

BGR = tuple[int, int, int]
SHIFT, ONE, FONT, AA = 4, 16, cv2.FONT_HERSHEY_SIMPLEX, cv2.LINE_AA  # 4-bit fixed point, text
TEAM_KNOWN, AT_BASE, WALL, SKELETON, FRONTIER, CLASSES = 1, 2, 3, 4, 5, 6
RUBBLE, DOOR, OBSTACLE = 253, 254, 255  # solid labels, above every class + tint (< 246)
_SOLID_COLOURS = {RUBBLE: "rubble", DOOR: "door", OBSTACLE: "obstacle"}
_CLASS_COLOURS = ("team_known", "known_at_base", "wall", "skeleton", "frontier")  # classes 1-5

PALETTE: tuple[BGR, ...] = (
    (180, 119, 31), (14, 127, 255), (189, 103, 148), (75, 86, 140), (207, 190, 23),
    (34, 189, 188), (128, 0, 0), (0, 100, 0), (255, 128, 128), (0, 128, 128),
)  # fmt: skip


@dataclass(frozen=True)
class Style:
    """Colours (BGR) and sizes, after the paper's Fig. 1 and the original GUI."""

    wall: BGR = (0, 0, 0)
    unexplored: BGR = (160, 160, 160)
    team_known: BGR = (255, 255, 255)
    known_at_base: BGR = (120, 200, 120)
    background: BGR = (255, 255, 255)  # a map class whose layer is off
    frontier: BGR = (255, 0, 255)
    skeleton: BGR = (0, 90, 200)
    terrain: BGR = (20, 60, 110)  # dark brown: slow ground is tinted toward it
    terrain_alpha: float = 0.7  # tint of the slowest ground (factor -> 0); factor 1: none
    ground_alpha: float = 0.45  # tint of a ground class toward its colour (ground/)
    prior: BGR = (200, 110, 40)  # blue: walls of the prior map where the truth is free
    prior_alpha: float = 0.5
    lost_knowledge: BGR = (60, 20, 220)  # crimson: cells only a failed robot knew
    ghost_wall: BGR = (20, 180, 210)  # dark yellow: walls an agent believes where it is free
    lost_alpha: float = 0.6
    banner: BGR = (40, 40, 200)  # the header's failure line
    hazard: BGR = (0, 80, 255)  # orange-red: hazard zones (fire, water)
    hazard_alpha: float = 0.35  # tint of a hazard zone's free cells
    partial: BGR = (0, 165, 255)  # orange ring: a robot with a part failed or degraded
    link: BGR = (128, 128, 0)
    hierarchy: BGR = (130, 0, 75)
    failed: BGR = (128, 128, 128)
    idle: BGR = (175, 175, 175)  # grey fill of an idle robot (outlined in its colour)
    stuck: BGR = (0, 0, 230)  # red ring around a stuck robot
    error: BGR = (0, 0, 255)
    base: BGR = (0, 0, 0)
    header_bg: BGR = (40, 40, 40)
    header_text: BGR = (255, 255, 255)
    legend_bg: BGR = (235, 235, 235)
    obstacle: BGR = (30, 30, 200)  # moving obstacles: deep red
    door: BGR = (0, 190, 255)  # doors: amber (closed: filled cells; open: dashed line)
    rubble: BGR = (50, 90, 130)  # rubble that fell during the run: brown
    meeting_kept: BGR = (0, 170, 0)  # green ring: a meeting kept (render.meetings)
    meeting_missed: BGR = (0, 0, 220)  # red cross: a meeting missed
    palette: tuple[BGR, ...] = PALETTE
    free_alpha: float = 0.3
    safe_alpha: float = 0.55
    robot_px: float = 6.0  # smallest robot glyph radius, pixels
    font_scale: float = 0.4

    def robot_colour(self, index: int) -> BGR:
        """Colour of the ``index``-th robot (the palette cycles)."""
        return self.palette[index % len(self.palette)]

    def lut(self, layers: LayerSpec) -> np.ndarray:
        """(256, 1, 3) uint8 table: label (class + 6 * tint, or a solid label) -> BGR."""
        blank = self.unexplored if "unexplored" in layers.global_layers else self.background
        base = np.array([blank] + [getattr(self, name) for name in _CLASS_COLOURS])
        n, table = len(self.palette), np.zeros((256, 1, 3), dtype=np.uint8)
        if not 1 <= n <= 20:  # 6 classes * (1 + 2 * 20 tints) < 256
            raise ValueError("Style.palette needs 1 to 20 colours")
        alpha = np.repeat((self.free_alpha, self.safe_alpha), n)[:, None, None]
        mixed = np.round((1 - alpha) * base + alpha * np.array(self.palette * 2)[:, None])
        mixed[:, AT_BASE + 1 :] = base[AT_BASE + 1 :]  # (tint, class, BGR); walls stay black
        table[: CLASSES * (2 * n + 1), 0] = np.concatenate((base, mixed.reshape(-1, 3)))
        for label, name in _SOLID_COLOURS.items():
            table[label, 0] = getattr(self, name)
        return table


DEFAULT_STYLE = Style()
