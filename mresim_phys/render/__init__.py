"""Views (phase 8): snapshots rendered as BGR frames with OpenCV, with the layers one picks.

Modules, each importing only the ones before it: ``layers`` (layer names, LayerSpec,
``--layers`` parsing), ``style`` (colours, sizes, label classes), ``raster`` (numba label
grid), ``draw`` (cv2 overlays) and ``frame`` (:class:`Renderer`, the two stages together).

Typical use: ``Renderer(truth.shape, parse_layers("all")).render(snapshot)``.
"""

from __future__ import annotations

from mresim_phys.render.frame import MIN_FRAME_SIDE, Renderer, frame_scale
from mresim_phys.render.layers import (
    DEFAULT_GLOBAL,
    DEFAULT_ROBOT,
    DEFAULTS,
    GLOBAL_LAYERS,
    LAYERS,
    ROBOT_LAYERS,
    LayerSpec,
    parse_layers,
)
from mresim_phys.render.style import BGR, DEFAULT_STYLE, PALETTE, Style

__all__ = [
    "BGR",
    "DEFAULTS",
    "DEFAULT_GLOBAL",
    "DEFAULT_ROBOT",
    "DEFAULT_STYLE",
    "GLOBAL_LAYERS",
    "LAYERS",
    "MIN_FRAME_SIDE",
    "PALETTE",
    "ROBOT_LAYERS",
    "LayerSpec",
    "Renderer",
    "Style",
    "frame_scale",
    "parse_layers",
]
