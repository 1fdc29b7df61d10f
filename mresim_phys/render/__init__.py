"""Views (phase 8): snapshots rendered as BGR frames with OpenCV, with the layers one picks.

Modules, each importing only the ones before it: ``layers`` (layer names, LayerSpec,
``--layers`` parsing), ``style`` (colours, sizes, label classes), ``raster`` (numba label
grid), ``pose`` (believed poses), ``draw`` (cv2 overlays) and ``frame``
(:class:`Renderer`, the two stages together).

Typical use: ``Renderer(truth.shape, parse_layers("all")).render(snapshot)``. Importing
the package is light (``layers``: a scenario's ``render`` block is validated without
OpenCV); ``Renderer``, ``Style`` and the other drawing names come from ``frame`` and
``style`` on first use.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

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

if TYPE_CHECKING:
    from mresim_phys.render.frame import MIN_FRAME_SIDE, Renderer, frame_scale
    from mresim_phys.render.style import BGR, DEFAULT_STYLE, PALETTE, Style

DRAWING = {  # name -> the module (OpenCV behind it) it comes from, on first use
    **dict.fromkeys(("MIN_FRAME_SIDE", "Renderer", "frame_scale"), "frame"),
    **dict.fromkeys(("BGR", "DEFAULT_STYLE", "PALETTE", "Style"), "style"),
}


def __getattr__(name: str) -> object:
    """The renderer's and the style's names, imported when first asked for."""
    if name in DRAWING:
        return getattr(importlib.import_module(f"{__name__}.{DRAWING[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


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
