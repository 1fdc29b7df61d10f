"""Views (phase 8), renderer: a run snapshot as a BGR frame, with the layers the user picks.

Raster stage (:mod:`~mresim_phys.render.raster`), at grid resolution: a uint8 label per
cell, class (0 unexplored, 1 team-known, 2 known at base, 3 wall, 4 skeleton, 5 frontier;
the larger wins) + 6 * free/safe space tint (later robots over earlier), coloured by one
lookup table (:meth:`Style.lut <mresim_phys.render.style.Style.lut>`) and resized once;
a changing world's rubble, closed doors and moving obstacles are solid labels over them.
Vector stage (:mod:`~mresim_phys.render.draw`), in output pixels with cv2 primitives: comm
ranges, links, hierarchy, paths, goals, rendezvous points, believed poses, robots, names,
header and legend.
Modules import downwards only: ``layers`` <- ``style`` <- ``raster``, ``labels``,
``legend``, ``pose`` <- ``draw`` <- ``frame``.
On an 8-robot 800x600 office frame with every layer on, a new snapshot each frame costs
~2-3 ms (``benchmarks/bench_render.py``; the numpy/cv2 renderer it replaced took 6-8 ms).

Typical use: ``Renderer(truth.shape, parse_layers("all")).render(snapshot)``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import cv2
import numpy as np

from mresim_phys.render.draw import Overlay
from mresim_phys.render.layers import LayerSpec
from mresim_phys.render.raster import (
    LabelGrids,
    colour_labels,
    packed_colours,
    shade_ghosts,
    shade_ground,
    shade_hazards,
    shade_lost,
    shade_prior,
    shade_terrain,
)
from mresim_phys.render.style import DEFAULT_STYLE, ONE, Style

if TYPE_CHECKING:
    from mresim_phys.comms.regions import RegionProbe
    from mresim_phys.snapshot import Snapshot

_AREA = cv2.INTER_AREA
MIN_FRAME_SIDE = 640  # output pixels: the longer side of a run's frames is at least this


def frame_scale(
    truth_shape: tuple[int, int], scale: float, min_side: int = MIN_FRAME_SIDE
) -> float:
    """``scale`` times the smallest whole factor that makes the frame's longer side at least
    ``min_side`` pixels, so the header and legend fit on small maps (a 160x120 map at scale
    1 is drawn at scale 4, 640x480; ``render.min_side``, 0: exactly ``scale``)."""
    longer = max(truth_shape) * scale
    return scale * max(1, math.ceil(min_side / longer)) if longer > 0 else scale


class Renderer:
    """Render snapshots of one map as BGR frames of a fixed, even size (one thread at a time).

    Args:
        truth_shape: (rows, cols) of the map grid.
        layers: Layers to draw.
        scale: Output pixels per cell.
        style: Colours and sizes.
        regions: Gives agents' communication-region polygons for the ``comm_range``
            layer (``comms.regions.RegionProbe``); without it, or for ``disk``, circles.
    """

    def __init__(
        self, truth_shape: tuple[int, int], layers: LayerSpec, scale: float = 1.0,
        style: Style = DEFAULT_STYLE, regions: RegionProbe | None = None,
    ) -> None:  # fmt: skip
        if scale <= 0:
            raise ValueError(f"scale must be positive, got {scale}")
        self.rows, self.cols = (int(n) for n in truth_shape)
        self.layers, self.scale, self.style = layers, float(scale), style
        self.map_size = (max(round(self.cols * scale), 1), max(round(self.rows * scale), 1))
        width, height = (max(n + n % 2, 2) for n in self.map_size)
        self.size = (width, height)  # output pixels, even
        self._to_px = np.array(self.map_size) / (self.cols, self.rows) * ONE
        self._lut = style.lut(layers)
        self._table = packed_colours(self._lut)
        self._overlay = Overlay(layers, style, self.scale, self._to_px)
        self.regions = regions
        # Scratch grids reused by every frame (fresh ones cost page faults at every frame).
        self._grids = LabelGrids((self.rows, self.cols))
        self._big = np.empty(self.map_size[::-1], dtype=np.uint8)

    def px(self, xy: Sequence[float] | np.ndarray) -> np.ndarray:
        """World (x, y) points -> fixed-point output pixel coordinates (int32, 4 bits)."""
        return self._overlay.px(xy)

    def render(self, snapshot: Snapshot) -> np.ndarray:
        """The frame of ``snapshot``: (height, width, 3) uint8 BGR; the snapshot is not changed."""
        if snapshot.truth.shape != (self.rows, self.cols):
            raise ValueError(f"snapshot map {snapshot.truth.shape} != {(self.rows, self.cols)}")
        label = self._grids.labels(snapshot, self.layers, len(self.style.palette))
        image = self._colour(label)
        if snapshot.terrain is not None and "terrain" in self.layers.global_layers:
            shade_terrain(image, snapshot.terrain, snapshot.truth, self.map_size, self.style)
        if snapshot.ground is not None and "ground" in self.layers.global_layers:
            shade_ground(image, snapshot.ground, snapshot.truth, self.map_size, self.style)
        if snapshot.prior is not None and "prior" in self.layers.global_layers:
            shade_prior(image, snapshot.prior, snapshot.truth, self.map_size, self.style)
        if snapshot.lost_knowledge is not None and "lost_knowledge" in self.layers.global_layers:
            shade_lost(image, snapshot.lost_knowledge, self.map_size, self.style)
        shade_ghosts(image, snapshot, self.layers, self.map_size, self.style)
        if snapshot.hazards is not None and "hazards" in self.layers.global_layers:
            shade_hazards(image, snapshot.hazards, snapshot.truth, self.map_size, self.style)
        self._overlay.draw(image, snapshot, self._regions(snapshot))
        return image

    def _regions(self, snapshot: Snapshot) -> list[np.ndarray | None]:
        """Region polygons of the agents that show their comm range ([] for circles)."""
        probe = self.regions
        if probe is None or probe.circles:
            return []
        shown = ["comm_range" in self.layers.for_agent(a.name) for a in snapshot.agents]
        if not any(shown):
            return []
        polygons = probe(np.array([a.position for a in snapshot.agents], dtype=float))
        return [p if on else None for p, on in zip(polygons, shown, strict=True)]

    def _colour(self, label: np.ndarray) -> np.ndarray:
        """Colour the label grid and resize it to the output size (padded to even)."""
        (mw, mh), (w, h) = self.map_size, self.size
        if mw < self.cols:  # downscale colours (area averaging), then pad
            image = cv2.resize(cv2.applyColorMap(label, self._lut), (mw, mh), None, 0, 0, _AREA)
            pad = [int(v) for v in self._lut[0, 0]]
            return cv2.copyMakeBorder(image, 0, h - mh, 0, w - mw, cv2.BORDER_CONSTANT, value=pad)
        if (mw, mh) != label.shape[::-1]:  # upscale labels (nearest), then colour
            label = cv2.resize(label, (mw, mh), self._big, 0, 0, cv2.INTER_NEAREST)
        image = np.empty((h, w, 3), dtype=np.uint8)
        colour_labels(label, self._table, image)
        return image
