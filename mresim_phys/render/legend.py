"""Views (phase 8), legend: the band at the bottom of a frame that says what is what.

Colour swatches for the map classes shown, the changing world's parts a frame holds
(:func:`world_legend`: obstacles, doors, rubble, hazard zones) and every robot; then, when
robots are drawn, the glyphs of a robot that is done, idle, stuck or fruitless (the run-health
record's activity, ``knowledge/health.py``), as ``render.draw`` draws them on the map; then
the marks a frame holds (``believed pose``: the hollow circle ``render.pose`` draws where a
robot with localisation believes it is; ``meeting kept`` and ``meeting missed``:
``render.meetings``).

Typical use: ``legend_band(width, names, layers, style, world_legend(snap, on))``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import cv2
import numpy as np

from mresim_phys.render.layers import LayerSpec
from mresim_phys.render.meetings import KEPT, MISSED, legend_mark
from mresim_phys.render.style import AA, BGR, FONT, ONE, SHIFT, Style

if TYPE_CHECKING:
    from mresim_phys.snapshot import Snapshot

LEGEND = {"walls": "wall", "unexplored": "unexplored", "team_known": "team_known"}
LEGEND["known_at_base"] = "known_at_base"  # global layer -> Style colour, in legend order
STATE_GLYPHS = ("done", "idle", "stuck", "fruitless")  # legend entries of robots not at work
GLYPH_COLOUR: BGR = (90, 90, 90)  # the legend's robot glyphs (a robot's own colour on frames)
BELIEVED = "believed pose"  # the legend mark of a believed pose (``render.pose``)


Swatch = str | tuple[str, tuple[int, int, int]]  # a Style colour name, or (label, BGR)


def world_legend(snap: Snapshot, on: frozenset[str]) -> tuple[Swatch, ...]:
    """The world's legend entries a frame shows: obstacle and door if the run has them,
    rubble once some has fallen, hazard zones (Style colour names), then the ground
    classes with their colours (a static run without faults or ground: none)."""
    kinds = {m.kind for m in snap.movables}
    rubble = snap.rubble is not None and bool(snap.rubble.any())
    present = [("obstacle", "obstacles", "obstacle" in kinds), ("door", "doors", "door" in kinds)]
    present.append(("rubble", "debris", rubble))
    present.append(("hazard", "hazards", snap.hazards is not None))
    names: tuple[Swatch, ...] = tuple(n for n, layer, shown in present if shown and layer in on)
    ground = snap.ground
    if ground is None or "ground" not in on:
        return names
    classes = ((n, (c[2], c[1], c[0])) for n, c in zip(ground.names, ground.colours, strict=True))
    return (*names, *classes)


def legend_band(
    width: int, names: Sequence[str], layers: LayerSpec, style: Style,
    extras: Sequence[Swatch] = (), marks: Sequence[str] = (),
) -> np.ndarray:  # fmt: skip
    """A band image with colour swatches for the map classes shown, the changing world's
    ``extras`` (Style colour names) and every robot, then (when robots are drawn) the
    glyphs of a robot that is done, idle, stuck or fruitless (:data:`STATE_GLYPHS`), then
    the glyphs of ``marks`` (:data:`BELIEVED`)."""
    on = layers.global_layers
    robot_layers = set(layers.robot_layers).union(*layers.per_robot.values())
    items = [
        (name.replace("_", " "), getattr(style, name)) for key, name in LEGEND.items() if key in on
    ]
    if "frontiers" in robot_layers:
        items.append(("frontier", style.frontier))
    if "ghost_walls" in robot_layers:
        items.append(("ghost wall", style.ghost_wall))
    items += [(e, getattr(style, e)) if isinstance(e, str) else e for e in extras]
    items += [(name, style.robot_colour(i)) for i, name in enumerate(names)]
    glyphs = (*(STATE_GLYPHS if "location" in robot_layers else ()), *marks)
    (_, th), base = cv2.getTextSize("Ag", FONT, style.font_scale, 1)
    line, spots, x, y = th + base + 4, [], 4, 0
    for text, colour in [*items, *((g, GLYPH_COLOUR) for g in glyphs)]:
        w = cv2.getTextSize(text, FONT, style.font_scale, 1)[0][0] + th + 12
        x, y = (4, y + line) if x + w > width and x > 4 else (x, y)
        spots.append((x, y, text, colour))
        x += w
    band = np.full((y + line + 2, width, 3), style.legend_bg, dtype=np.uint8)
    for n, (x, y, text, colour) in enumerate(spots):
        if n < len(items):
            cv2.rectangle(band, (x, y + 3), (x + th, y + 3 + th), colour, -1)
            cv2.rectangle(band, (x, y + 3), (x + th, y + 3 + th), (60, 60, 60), 1)
        else:
            legend_glyph(band, text, (x, y + 3), th, style)
        org = (x + th + 4, y + 3 + th)
        cv2.putText(band, text, org, FONT, style.font_scale, (0, 0, 0), 1, AA)
    return band


def legend_glyph(
    band: np.ndarray, kind: str, corner: tuple[int, int], side: int, style: Style
) -> None:
    """A small robot glyph in the ``side``-pixel square at ``corner``, drawn as a robot
    that is ``kind`` (done, idle, stuck or fruitless) is drawn on a frame, or the believed
    pose mark (:data:`BELIEVED`: a hollow circle), in :data:`GLYPH_COLOUR`."""
    x, y = corner
    if kind in (KEPT, MISSED):
        legend_mark(band, kind, corner, side, style)
        return
    if kind == BELIEVED:
        centre = ((2 * x + side) * ONE // 2, (2 * y + side) * ONE // 2)
        cv2.circle(band, centre, (side * ONE) // 2 - ONE // 2, GLYPH_COLOUR, 2, AA, SHIFT)
        return
    tip, back = (x + side) * ONE, x * ONE + ONE
    pts = np.array([[tip, (y + side // 2) * ONE], [back, y * ONE], [back, (y + side) * ONE]])
    pts = pts.astype(np.int32)
    if kind == "done":
        cv2.polylines(band, [pts], True, GLYPH_COLOUR, 1, AA, SHIFT)
    elif kind == "idle":
        cv2.fillPoly(band, [pts], style.idle, AA, SHIFT)
        cv2.polylines(band, [pts], True, GLYPH_COLOUR, 1, AA, SHIFT)
    else:
        cv2.fillPoly(band, [pts], GLYPH_COLOUR, AA, SHIFT)
        centre = ((2 * x + side) * ONE // 2, (2 * y + side) * ONE // 2)
        ring = style.stuck if kind == "stuck" else style.idle
        cv2.circle(band, centre, (side * ONE) // 2 + ONE, ring, 1, AA, SHIFT)
