"""Views (phase 8), vector stage: what a frame shows in output pixels, over the coloured map.

Open doors (dashed lines) and moving obstacles' names, comm ranges, links, hierarchy,
paths, goals, rendezvous points, believed poses (``render.pose``), robots (a done, idle or
stuck one unlike a working one), names (placed apart: ``render.labels``), header and legend
(``render.legend``), bottom to top, with cv2 primitives in 4-bit fixed point
(anti-aliased). Points are converted to pixels in one numpy call per frame (every agent,
every path point, every goal), robot triangles in another, and all links are one
``cv2.polylines`` call; the drawing order (and so every blended pixel) is the same as one
robot at a time. The legend band is drawn once per set of robot names (and world legend
entries and marks) and pasted.

Typical use: ``Overlay(layers, style, scale, to_px).draw(image, snapshot)``.
"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from typing import TYPE_CHECKING

import cv2
import numpy as np

from mresim_phys.broken_parts import PARTS
from mresim_phys.features import FEATURES
from mresim_phys.knowledge.activity import health_of
from mresim_phys.render.labels import Label, place_labels
from mresim_phys.render.layers import LayerSpec
from mresim_phys.render.legend import BELIEVED, Swatch, legend_band
from mresim_phys.render.legend import world_legend as world_legend
from mresim_phys.render.meetings import draw_meetings, meeting_marks
from mresim_phys.render.pose import draw_beliefs, path_start, shows_beliefs
from mresim_phys.render.scale_bar import draw_scale_bar
from mresim_phys.render.style import AA, BGR, FONT, ONE, SHIFT, Style

if TYPE_CHECKING:
    from mresim_phys.snapshot import AgentSnapshot, Snapshot

TRIANGLE_TURNS = np.array((0.0, 2.4, -2.4))  # radians from the heading: tip, two corners
TRIANGLE_REACH = np.array((1.6, 1.0, 1.0))  # in robot glyph sizes
FAR_PX = 2**24  # fixed-point pixels (a million whole pixels): farther points are clipped here
BANNER_STEPS = 40  # a failure's banner line stays in the header this many steps
DASH_PX = 6  # length of a dash of an open door's line, pixels
CROSS_ARMS = np.array(((1, 1), (1, -1)), dtype=np.int32) * ONE  # half-diagonals of an 'x'


class Overlay:
    """The vector stage of one renderer (one thread at a time).

    Args:
        layers: Layers to draw.
        style: Colours and sizes.
        scale: Output pixels per cell.
        to_px: (2,) output fixed-point units per cell along x and y.
    """

    def __init__(self, layers: LayerSpec, style: Style, scale: float, to_px: np.ndarray) -> None:
        self.layers, self.style, self.scale, self.to_px = layers, style, scale, to_px
        self._legend: tuple[tuple[tuple[Swatch, ...], ...], np.ndarray] | None = None

    def px(self, xy: Sequence[float] | np.ndarray) -> np.ndarray:
        """World (x, y) points -> fixed-point output pixel coordinates (int32, 4 bits)."""
        pixels: np.ndarray = np.round(np.asarray(xy, dtype=float) * self.to_px - ONE / 2)
        # far-away points (a comm region of a huge path-loss budget) are pulled in to a
        # million pixels off the frame: cv2 clips what it draws there, int32 must not wrap
        clipped: np.ndarray = np.clip(pixels, -FAR_PX, FAR_PX).astype(np.int32)
        return clipped

    def draw(
        self, image: np.ndarray, snap: Snapshot, regions: Sequence[np.ndarray | None] = ()
    ) -> None:
        """Everything drawn in output pixels, bottom to top.

        ``regions`` are agents' communication-region polygons (world points), drawn
        instead of the range circle where given.
        """
        on, style = self.layers.global_layers, self.style
        layers = [self.layers.for_agent(a.name) for a in snap.agents]
        colours = [style.base, *(style.robot_colour(i) for i in range(len(snap.robots)))]
        centres, paths, goals = self._points(snap, layers)
        self._draw_world(image, snap)
        self._draw_network(image, snap, centres, colours, layers, regions)
        for i, robot in enumerate(snap.robots, start=1):
            self._draw_plans(image, robot, paths[i], goals[i], colours[i], layers[i])
        if "meetings" in on and snap.meetings is not None:
            draw_meetings(image, snap.meetings, self.px, style)
        sizes = [max(style.robot_px, robot.radius * self.scale) for robot in snap.robots]
        draw_beliefs(
            image, snap.robots, centres[1:], colours[1:], layers[1:], self.px, self.to_px, sizes
        )
        labels = iter(self._labels(snap, layers, centres, sizes))
        if "location" in layers[0]:
            c, half = centres[0], 5 * ONE
            cv2.rectangle(image, c - half, c + half, style.base, -1, cv2.LINE_8, SHIFT)
            draw_text(image, *next(labels), style.base, style)
        triangles = robot_triangles(snap.robots, centres[1:], sizes)
        for i, robot in enumerate(snap.robots, start=1):
            if "location" in layers[i]:
                at, size = centres[i], sizes[i - 1]
                draw_robot(image, robot, triangles[i - 1], at, size, colours[i], style)
                if PARTS.of(robot) and robot.state != "failed":
                    draw_ring(image, at, size, style.partial)
                draw_text(image, *next(labels), colours[i], style)
        if "header" in on:
            draw_header(image, snap, style, snap.dt)
        legend = 0
        if "legend" in on:
            believed = (BELIEVED,) if shows_beliefs(snap.robots, layers[1:]) else ()
            marks = (*believed, *meeting_marks(snap.meetings, on))
            legend = self._paste_legend(image, tuple(r.name for r in snap.robots),
                                        world_legend(snap, on), marks)  # fmt: skip
        if "scale_bar" in on and snap.resolution is not None:
            rows, cols = snap.truth.shape
            height = min(round(rows * self.scale), image.shape[0] - legend)
            draw_scale_bar(image, (round(cols * self.scale), height), self.scale,
                           snap.resolution, style)  # fmt: skip

    def _labels(
        self,
        snap: Snapshot,
        layers: list[frozenset[str]],
        centres: np.ndarray,
        sizes: Sequence[float],
    ) -> list[tuple[str, tuple[int, int]]]:
        """(text, text origin) of the label of every agent drawn (base first), placed
        apart (``render.labels``)."""
        labels: list[Label] = []
        offsets = [5.0, *sizes]
        for agent, mine, centre, offset in zip(snap.agents, layers, centres, offsets, strict=True):
            if "location" in mine:
                text = robot_label(agent, mine)
                labels.append((text, (int(centre[0]) >> SHIFT, int(centre[1]) >> SHIFT), offset))
        origins = place_labels(labels, self.style)
        return [(label[0], org) for label, org in zip(labels, origins, strict=True)]

    def _points(
        self, snap: Snapshot, layers: list[frozenset[str]]
    ) -> tuple[np.ndarray, list[np.ndarray | None], list[np.ndarray | None]]:
        """Pixel centres of all agents and, per agent, its drawn path (from its position,
        or its believed one with localisation: ``render.pose``) and goal (None where not
        drawn; the base has neither), converted in one call."""
        pieces = [np.array([a.position for a in snap.agents], dtype=float)]
        drawn = [(0, False)]  # per agent: points in its drawn path, goal drawn
        for robot, mine in zip(snap.robots, layers[1:], strict=True):
            path = len(robot.path) + 1 if "path" in mine and len(robot.path) else 0
            goal = "goal" in mine and robot.goal is not None
            if path:
                pieces += [np.reshape(path_start(robot), (1, 2)), np.asarray(robot.path, float)]
            if goal:
                pieces.append(np.reshape(np.asarray(robot.goal, float), (1, 2)))
            drawn.append((path, goal))
        points = self.px(np.concatenate(pieces))
        paths: list[np.ndarray | None] = []
        goals: list[np.ndarray | None] = []
        start = len(snap.agents)
        for path, goal in drawn:
            paths.append(points[start : start + path] if path else None)
            goals.append(points[start + path] if goal else None)
            start += path + goal
        return points[: len(snap.agents)], paths, goals

    def _draw_network(
        self,
        image: np.ndarray,
        snap: Snapshot,
        centres: np.ndarray,
        colours: list[BGR],
        layers: list[frozenset[str]],
        regions: Sequence[np.ndarray | None],
    ) -> None:
        """Comm range circles (or region polygons), links and hierarchy (parent) lines."""
        polygons = list(regions) or [None] * len(snap.agents)
        for agent, c, colour, mine, polygon in zip(
            snap.agents, centres, colours, layers, polygons, strict=True
        ):
            if "comm_range" not in mine or agent.comm_range <= 0:
                continue
            if polygon is not None:
                cv2.polylines(image, [self.px(polygon)], True, colour, 1, AA, SHIFT)
            else:
                radius = round(agent.comm_range * self.scale * ONE)
                cv2.circle(image, c, radius, colour, 1, AA, SHIFT)
        on, index = self.layers.global_layers, {a.name: i for i, a in enumerate(snap.agents)}
        ends: np.ndarray | list[np.ndarray] = (
            centres[np.argwhere(np.triu(snap.links, 1))] if "links" in on else []
        )
        if len(ends):  # one call for all links: 1-pixel AA polylines draw as cv2.line does
            cv2.polylines(image, list(ends), False, self.style.link, 1, AA, SHIFT)
        if "hierarchy" in on:
            parents = [
                (i, index.get(a.parent) if a.parent is not None else None)
                for i, a in enumerate(snap.agents)
            ]
            for i, j in ((i, j) for i, j in parents if j is not None):
                cv2.line(image, centres[i], centres[j], self.style.hierarchy, 2, AA, SHIFT)

    def _draw_plans(
        self,
        image: np.ndarray,
        robot: AgentSnapshot,
        path: np.ndarray | None,
        goal: np.ndarray | None,
        colour: BGR,
        mine: frozenset[str],
    ) -> None:
        """A robot's path, goal and rendezvous points (each when its layer is on)."""
        if path is not None:
            cv2.polylines(image, [path], False, colour, 1, AA, SHIFT)
        if goal is not None:
            draw_cross(image, goal, 4, colour)
        marks = (
            ("rv_candidates", robot.rv_candidates, cv2.MARKER_SQUARE, 3, 1),
            ("rv_through_walls", robot.rv_through_walls, cv2.MARKER_TILTED_CROSS, 6, 1),
            ("rendezvous", robot.rendezvous, cv2.MARKER_DIAMOND, 8, 2),
        )
        for layer, points, marker, size, thickness in marks:
            if layer in mine and points is not None and len(points):
                for p in self.px(np.reshape(points, (-1, 2))) >> SHIFT:
                    cv2.drawMarker(image, p, colour, marker, size, thickness)

    def _draw_world(self, image: np.ndarray, snap: Snapshot) -> None:
        """Open doors as dashed lines along their segment (closed ones are cells of the
        raster stage) and moving obstacles' names, each when its layer is on."""
        on, style = self.layers.global_layers, self.style
        for movable in snap.movables:
            if movable.kind == "door" and not movable.on and movable.segment is not None:
                if "doors" in on:
                    lines = dashes(self.px(np.asarray(movable.segment)), DASH_PX * ONE)
                    cv2.polylines(image, lines, False, style.door, 2, AA, SHIFT)
            elif movable.kind == "obstacle" and movable.on and "obstacles" in on:
                h, w = movable.cells.shape
                centre = self.px(np.array([movable.at[1] + w / 2, movable.at[0] + h / 2]))
                draw_label(image, movable.name, centre, w / 2 * self.scale, style.obstacle, style)

    def _paste_legend(
        self, image: np.ndarray, names: tuple[str, ...], extras: tuple[Swatch, ...],
        marks: tuple[str, ...] = (),
    ) -> int:  # fmt: skip
        """The legend band over the bottom of ``image``; its height in pixels."""
        key = (names, extras, marks)
        if self._legend is None or self._legend[0] != key:
            band = legend_band(image.shape[1], names, self.layers, self.style, extras, marks)
            self._legend = (key, band)
        band = self._legend[1][-image.shape[0] :]
        image[image.shape[0] - band.shape[0] :] = band
        return int(band.shape[0])


def robot_triangles(
    robots: Sequence[AgentSnapshot], centres: np.ndarray, sizes: Sequence[float]
) -> np.ndarray:
    """(n, 3, 2) int32 fixed-point corners of every robot's triangle (tip along its heading)."""
    headings = np.array([robot.heading for robot in robots], dtype=float)
    angles = headings[:, None] + TRIANGLE_TURNS
    reach = TRIANGLE_REACH[None, :, None] * np.asarray(sizes, dtype=float)[:, None, None] * ONE
    units = np.stack((np.cos(angles), np.sin(angles)), axis=-1)
    corners: np.ndarray = (np.reshape(centres, (-1, 1, 2)) + units * reach).astype(np.int32)
    return corners


def draw_cross(image: np.ndarray, centre: np.ndarray, half: int, colour: BGR) -> None:
    """An 'x' of half-size ``half`` pixels at a fixed-point ``centre``."""
    for d in CROSS_ARMS * half:
        cv2.line(image, centre - d, centre + d, colour, 2, AA, SHIFT)


def draw_robot(
    image: np.ndarray,
    robot: AgentSnapshot,
    pts: np.ndarray,
    at: np.ndarray,
    size: float,
    colour: BGR,
    style: Style,
) -> None:
    """A triangle: filled (working), hollow (done), grey outlined in its colour (idle), red
    outline (error), dark grey + red X (failed); a red ring around a stuck robot, a grey
    one around a fruitless one (working while the team gains nothing)."""
    state, activity = robot.state, health_of(robot).activity
    if state == "done":
        cv2.polylines(image, [pts], True, colour, 2, AA, SHIFT)
    elif state != "failed" and activity == "idle":
        cv2.fillPoly(image, [pts], style.idle, AA, SHIFT)
        cv2.polylines(image, [pts], True, colour, 1, AA, SHIFT)
    else:
        cv2.fillPoly(image, [pts], style.failed if state == "failed" else colour, AA, SHIFT)
        outline, width = (style.error, 2) if state == "error" else ((0, 0, 0), 1)
        cv2.polylines(image, [pts], True, outline, width, AA, SHIFT)
    if state == "failed":
        draw_cross(image, at, max(round(size * 0.8), 3), style.error)
    elif activity in ("stuck", "fruitless"):
        centre = (int(at[0]), int(at[1]))
        ring = style.stuck if activity == "stuck" else style.idle
        cv2.circle(image, centre, round((size * 1.5 + 1) * ONE), ring, 2, AA, SHIFT)


def draw_ring(image: np.ndarray, at: np.ndarray, size: float, colour: BGR) -> None:
    """A ring around a robot (fixed-point centre ``at``): a part failed or degraded."""
    centre = (int(at[0]), int(at[1]))
    cv2.circle(image, centre, round((size * 1.9 + 2) * ONE), colour, 2, AA, SHIFT)


def robot_label(robot: AgentSnapshot, layers: Collection[str] = ()) -> str:
    """A robot's name, its features' labels (``features.py``: its failed parts if any, its
    battery level if it has one, and with the ``presumed_lost`` layer among ``layers`` the
    teammates it presumes lost), then what it is doing when that is not work (``done``,
    ``idle``, ``stuck``, ``fruitless``): ``B [radio] 73% lost?A idle``."""
    values = robot.features
    text = robot.name + "".join(
        f.label(values[f.key])
        for f in FEATURES.recorded()
        if f.key in values and (f.layer is None or f.layer in layers)
    )
    tag = state_tag(robot)
    return f"{text} {tag}" if tag else text


def state_tag(robot: AgentSnapshot) -> str:
    """``done``, ``idle``, ``stuck`` or ``fruitless`` (knowledge.health's activity), or
    ``""`` for a robot at work, a failed one (its grey X says it) and the base."""
    if robot.state == "done":
        return "done"
    activity = health_of(robot).activity
    shown = activity in ("idle", "stuck", "fruitless")
    return activity if shown and robot.state != "failed" else ""


def draw_label(
    image: np.ndarray, text: str, at: np.ndarray, offset: float, colour: BGR, style: Style
) -> None:
    """``text`` up and right of the fixed-point point ``at``, on a white halo."""
    x, y = (int(v) >> SHIFT for v in at)
    draw_text(image, text, (x + int(offset) + 2, y - int(offset) - 1), colour, style)


def draw_text(
    image: np.ndarray, text: str, org: tuple[int, int], colour: BGR, style: Style
) -> None:
    """``text`` from the pixel ``org`` (its baseline's left end), on a white halo."""
    cv2.putText(image, text, org, FONT, style.font_scale, (255, 255, 255), 3, AA)
    cv2.putText(image, text, org, FONT, style.font_scale, colour, 1, AA)


def draw_header(image: np.ndarray, snap: Snapshot, style: Style, dt: float | None = None) -> None:
    """Step (and its time, given ``dt`` seconds per step), explored %, known at base % and
    alive robots, in a band at the top; below it, for ``BANNER_STEPS`` steps after a
    failure, a red line naming it."""
    when = f"step {snap.step}" + (f" ({snap.step * dt:.1f} s)" if dt is not None else "")
    text = f"{when}   explored {snap.explored:.1%}   at base {snap.known_at_base:.1%}"
    text += f"   robots {snap.alive}/{len(snap.robots)}"
    (_, th), base = cv2.getTextSize(text, FONT, style.font_scale, 1)
    cv2.rectangle(image, (0, 0), (image.shape[1], th + base + 5), style.header_bg, -1)
    cv2.putText(image, text, (4, th + 3), FONT, style.font_scale, style.header_text, 1, AA)
    recent = [f"{what} at step {step}" for step, what in snap.failures
              if 0 <= snap.step - step < BANNER_STEPS]  # fmt: skip
    if recent:
        top, height = th + base + 5, th + base + 5
        cv2.rectangle(image, (0, top), (image.shape[1], top + height), style.banner, -1)
        line = "FAILED: " + ", ".join(recent)
        cv2.putText(image, line, (4, top + th + 3), FONT, style.font_scale, (255, 255, 255), 1, AA)


def dashes(ends: np.ndarray, dash: float) -> list[np.ndarray]:
    """A dashed line between the two fixed-point points ``ends``: an odd number of pieces
    about ``dash`` long (fixed point), every other one drawn, starting and ending drawn."""
    start, end = ends.astype(float)
    pieces = max(round(float(np.hypot(*(end - start))) / dash), 1)
    pieces += 1 - pieces % 2
    points = np.round(start + np.linspace(0.0, 1.0, pieces + 1)[:, None] * (end - start))
    points = points.astype(np.int32)
    return [points[i : i + 2] for i in range(0, pieces, 2)]
