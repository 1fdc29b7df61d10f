"""Views (phase 8), the scale bar: how long a metre is on the frame.

Drawn at the bottom right of the map, above the legend, when the map's resolution is known
(a ROS map's, or ``map.resolution``) and the ``scale_bar`` layer is on: a bar of a round
length (1, 2 or 5 times a power of ten metres) near a fifth of the map's width, with its
length written above it.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from mresim_phys.render.style import Style

FONT = cv2.FONT_HERSHEY_SIMPLEX
MARGIN_PX = 8


def round_length(metres: float) -> float:
    """The largest of 1, 2, 5 x 10^k metres not above ``metres``.

    >>> round_length(7.3), round_length(0.031), round_length(20.0)
    (5.0, 0.02, 20.0)
    """
    power = 10.0 ** math.floor(math.log10(metres))
    step = max(s for s in (1.0, 2.0, 5.0) if s * power <= metres * (1 + 1e-9))
    return float(f"{step * power:.6g}")


def label(metres: float) -> str:
    """``5 m``, ``20 cm``, ``1.5 km``.

    >>> label(5.0), label(0.2), label(2000.0)
    ('5 m', '20 cm', '2 km')
    """
    if metres >= 1000:
        return f"{metres / 1000:g} km"
    return f"{metres:g} m" if metres >= 1 else f"{metres * 100:g} cm"


def draw_scale_bar(
    image: np.ndarray,
    map_px: tuple[int, int],
    px_per_cell: float,
    resolution: float,
    style: Style,
) -> None:
    """The bar in ``image``, whose map covers ``map_px`` (width, height) pixels."""
    width, height = map_px
    metres = round_length(width / 5 / px_per_cell * resolution)
    length = max(1, round(metres / resolution * px_per_cell))
    right, bottom = width - MARGIN_PX, height - MARGIN_PX
    left = right - length
    text = label(metres)
    (tw, th), base = cv2.getTextSize(text, FONT, style.font_scale, 1)
    top = bottom - th - base - 8
    box = (max(0, min(left, right - tw) - 4), max(0, top - 2))
    cv2.rectangle(image, box, (width - 2, bottom + 4), (255, 255, 255), -1)
    cv2.rectangle(image, (left, bottom - 3), (right, bottom), (0, 0, 0), -1)
    for x in (left, right):
        cv2.line(image, (x, bottom - 7), (x, bottom), (0, 0, 0), 1)
    at = (right - tw, bottom - 8)
    cv2.putText(image, text, at, FONT, style.font_scale, (0, 0, 0), 1, cv2.LINE_AA)
