"""Views (phase 8), labels: where agents' names go so that they do not pile up.

Every agent's label is drawn up and right of its glyph unless that box overlaps a label
placed before it (agents in snapshot order: the base, then the robots). Then the first
free spot among a few others is taken, nearest first: down-right, up-left, down-left, then
stacked above and below the first spot, one text line at a time. A label that finds no
free spot (a crowd of robots) keeps the first one. Greedy and deterministic: the same
snapshot gives the same frame; a frame whose labels never touch is drawn as before.

Typical use: ``place_labels([(text, (x, y), offset), ...], style)`` -> text origins.
"""

from __future__ import annotations

from collections.abc import Sequence

import cv2

from mresim_phys.render.style import FONT, Style

HALO = 2  # pixels around a label's text that count as the label (its white halo)
STACKED = 4  # lines above and below the first spot tried before giving up
Rect = tuple[int, int, int, int]  # x0, y0, x1, y1 (pixels, half-open)
Label = tuple[str, tuple[int, int], float]  # text, anchor pixel (x, y), glyph size (pixels)


def text_box(text: str, org: tuple[int, int], style: Style) -> Rect:
    """The pixels ``text`` covers when ``cv2.putText`` draws it at ``org``, halo included."""
    (width, height), base = cv2.getTextSize(text, FONT, style.font_scale, 1)
    x, y = org
    return x - HALO, y - height - HALO, x + width + HALO, y + base + HALO


def overlaps(a: Rect, b: Rect) -> bool:
    """Whether two rectangles share a pixel.

    >>> overlaps((0, 0, 10, 10), (9, 9, 20, 20)), overlaps((0, 0, 10, 10), (10, 0, 20, 10))
    (True, False)
    """
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


def spots(text: str, anchor: tuple[int, int], offset: float, style: Style) -> list[tuple[int, int]]:
    """Text origins to try for a label, best first (module docstring)."""
    (width, height), base = cv2.getTextSize(text, FONT, style.font_scale, 1)
    x, y, gap = anchor[0], anchor[1], int(offset)
    right, left = x + gap + 2, x - gap - 2 - width
    up, down = y - gap - 1, y + gap + height + 1
    line = height + base + 2 * HALO
    out = [(right, up), (right, down), (left, up), (left, down)]
    for k in range(1, STACKED + 1):
        out += [(right, up - k * line), (right, down + k * line)]
    return out


def place_labels(labels: Sequence[Label], style: Style) -> list[tuple[int, int]]:
    """The text origin of every label, in order, each clear of those placed before it."""
    placed: list[Rect] = []
    origins = []
    for text, anchor, offset in labels:
        tried = spots(text, anchor, offset, style)
        boxes = [text_box(text, org, style) for org in tried]
        free = [k for k, box in enumerate(boxes) if not any(overlaps(box, p) for p in placed)]
        k = free[0] if free else 0
        origins.append(tried[k])
        placed.append(boxes[k])
    return origins
