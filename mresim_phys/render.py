"""Views (phase 8): a run snapshot as a BGR frame, with the layers the user picks.

Raster stage, at grid resolution: a uint8 label per cell, class (0 unexplored, 1 team-known,
2 known at base, 3 wall, 4 skeleton, 5 frontier; the larger wins) + 6 * free/safe space tint
(later robots over earlier), coloured by one lookup table and resized once. Vector stage, in
output pixels with cv2 primitives: comm ranges, links, hierarchy, paths, goals, rendezvous
points, robots, names, header and legend.
"""

from __future__ import annotations

import difflib
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType

import cv2
import numpy as np

from .render_raster import AT_BASE, CLASSES, LabelGrids, colour_labels, packed_colours
from .snapshot import AgentSnapshot, Snapshot
from .types import FREE, OCCUPIED, UNKNOWN

BGR = tuple[int, int, int]
GLOBAL_LAYERS = ("walls", "unexplored", "team_known", "known_at_base", "links", "hierarchy")
GLOBAL_LAYERS += ("legend", "header")
ROBOT_LAYERS = ("location", "path", "free_space", "safe_space", "frontiers", "comm_range")
ROBOT_LAYERS += ("goal", "skeleton", "rendezvous")
LAYERS = GLOBAL_LAYERS + ROBOT_LAYERS
DEFAULT_GLOBAL = frozenset(GLOBAL_LAYERS)
DEFAULT_ROBOT = frozenset(ROBOT_LAYERS) - {"free_space", "safe_space"}
DEFAULTS = DEFAULT_GLOBAL | DEFAULT_ROBOT
_KINDS = f"global layers: {', '.join(GLOBAL_LAYERS)}; robot layers: {', '.join(ROBOT_LAYERS)}"
_SHIFT, _ONE, _FONT, _AA = 4, 16, cv2.FONT_HERSHEY_SIMPLEX, cv2.LINE_AA  # 4-bit fixed point
_AREA = cv2.INTER_AREA
_CLASS_COLOURS = ("team_known", "known_at_base", "wall", "skeleton", "frontier")  # classes 1-5
_LEGEND = dict(zip(GLOBAL_LAYERS[:4], ("wall", *GLOBAL_LAYERS[1:4]), strict=True))  # -> colour
assert (UNKNOWN, FREE, OCCUPIED) == (0, 1, 2)  # FREE is odd: ``belief & 1`` is the FREE mask

PALETTE: tuple[BGR, ...] = (
    (180, 119, 31), (14, 127, 255), (189, 103, 148), (75, 86, 140), (207, 190, 23),
    (34, 189, 188), (128, 0, 0), (0, 100, 0), (255, 128, 128), (0, 128, 128),
)  # fmt: skip


@dataclass(frozen=True)
class LayerSpec:
    """Layers to draw: global, per robot, and whole robot sets for named agents (or the base)."""

    global_layers: frozenset[str] = DEFAULT_GLOBAL
    robot_layers: frozenset[str] = DEFAULT_ROBOT
    per_robot: Mapping[str, frozenset[str]] = field(default_factory=dict, hash=False)

    def __post_init__(self) -> None:
        per_robot = {name: frozenset(ls) for name, ls in self.per_robot.items()}
        object.__setattr__(self, "global_layers", frozenset(self.global_layers))
        object.__setattr__(self, "robot_layers", frozenset(self.robot_layers))
        object.__setattr__(self, "per_robot", MappingProxyType(per_robot))
        bad = set(self.global_layers) - set(GLOBAL_LAYERS)
        bad |= set().union(self.robot_layers, *per_robot.values()) - set(ROBOT_LAYERS)
        if bad:
            raise ValueError(f"misplaced or unknown layers {sorted(bad)} ({_KINDS})")

    @classmethod
    def all(cls) -> LayerSpec:
        """Every layer on."""
        return cls(frozenset(GLOBAL_LAYERS), frozenset(ROBOT_LAYERS))

    def for_agent(self, name: str) -> frozenset[str]:
        """The layers drawn for the agent called ``name``."""
        return self.per_robot.get(name, self.robot_layers)

    def check_agents(self, names: Iterable[str]) -> None:
        """Raise ValueError if an override names no agent in ``names`` (with close matches)."""
        for name in sorted(set(self.per_robot).difference(names := list(names))):
            raise ValueError(f"layers: no robot {name!r}{_close(name, names)}")


def _close(word: str, choices: Sequence[str]) -> str:
    matches = difflib.get_close_matches(word, choices, n=3, cutoff=0.5)
    return f"; did you mean {', '.join(matches)}?" if matches else ""


def _expand(word: str, allowed: Sequence[str] = LAYERS) -> frozenset[str]:
    """One layer name or keyword of ``parse_layers`` as a set of layer names."""
    if word in ("all", "default"):
        return (frozenset(LAYERS) if word == "all" else DEFAULTS) & frozenset(allowed)
    if word in allowed:
        return frozenset((word,))
    if word in LAYERS:
        raise ValueError(f"layer {word!r} is global: it cannot be chosen for one robot")
    hint = _close(word, (*LAYERS, "all", "default"))
    raise ValueError(f"unknown layer {word!r}{hint} ({_KINDS}; keywords: all, default)")


def _apply(start: set[str], changes: Iterable[tuple[str, str]], allowed: Sequence[str]) -> set[str]:
    for sign, word in changes:
        words = _expand(word, allowed)
        start = start - words if sign == "-" else start | words
    return start


def parse_layers(text: str) -> LayerSpec:
    """Parse a ``--layers`` value: comma-separated tokens, applied in order.

    ``name`` adds a layer, ``-name`` removes it, ``all`` / ``default`` add those sets, and
    ``B:free_space+path-goal`` changes robot B's layers relative to the common ones. With no
    adding token, the defaults are the start: ``"-links,B:free_space"``; ``""`` = defaults.

    Raises:
        ValueError: On an unknown layer (with close matches) or a malformed token.
    """
    tokens = [re.sub(r"\s", "", t) for t in text.split(",") if t.strip()]
    plain = [("-" if t[0] == "-" else "", t.lstrip("-")) for t in tokens if ":" not in t]
    adds = any(sign == "" for sign, _ in plain)
    chosen = _apply(set() if adds else set(DEFAULTS), plain, LAYERS)
    robot, per_robot = chosen & set(ROBOT_LAYERS), {}
    for token in (t for t in tokens if ":" in t):
        name, _, rest = token.partition(":")
        if not name or not re.fullmatch(r"[+-]?\w+([+-]\w+)*", rest):
            raise ValueError(f"layers: {token!r} should look like 'B:free_space+path-goal'")
        changes = re.findall(r"([+-]?)(\w+)", rest)
        per_robot[name] = _apply(set(per_robot.get(name, robot)), changes, ROBOT_LAYERS)
    return LayerSpec(frozenset(chosen & set(GLOBAL_LAYERS)), frozenset(robot), per_robot)


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
    link: BGR = (128, 128, 0)
    hierarchy: BGR = (130, 0, 75)
    failed: BGR = (128, 128, 128)
    error: BGR = (0, 0, 255)
    base: BGR = (0, 0, 0)
    header_bg: BGR = (40, 40, 40)
    header_text: BGR = (255, 255, 255)
    legend_bg: BGR = (235, 235, 235)
    palette: tuple[BGR, ...] = PALETTE
    free_alpha: float = 0.3
    safe_alpha: float = 0.55
    robot_px: float = 6.0  # smallest robot glyph radius, pixels
    font_scale: float = 0.4

    def robot_colour(self, index: int) -> BGR:
        """Colour of the ``index``-th robot (the palette cycles)."""
        return self.palette[index % len(self.palette)]

    def lut(self, layers: LayerSpec) -> np.ndarray:
        """(256, 1, 3) uint8 table: label (class + 6 * tint) -> BGR."""
        blank = self.unexplored if "unexplored" in layers.global_layers else self.background
        base = np.array([blank] + [getattr(self, name) for name in _CLASS_COLOURS])
        n, table = len(self.palette), np.zeros((256, 1, 3), dtype=np.uint8)
        if not 1 <= n <= 20:  # 6 classes * (1 + 2 * 20 tints) < 256
            raise ValueError("Style.palette needs 1 to 20 colours")
        alpha = np.repeat((self.free_alpha, self.safe_alpha), n)[:, None, None]
        mixed = np.round((1 - alpha) * base + alpha * np.array(self.palette * 2)[:, None])
        mixed[:, AT_BASE + 1 :] = base[AT_BASE + 1 :]  # (tint, class, BGR); walls stay black
        table[: CLASSES * (2 * n + 1), 0] = np.concatenate((base, mixed.reshape(-1, 3)))
        return table


DEFAULT_STYLE = Style()


class Renderer:
    """Render snapshots of one map as BGR frames of a fixed, even size (one thread at a time).

    Args:
        truth_shape: (rows, cols) of the map grid.
        layers: Layers to draw.
        scale: Output pixels per cell.
        style: Colours and sizes.
    """

    def __init__(
        self, truth_shape: tuple[int, int], layers: LayerSpec, scale: float = 1.0,
        style: Style = DEFAULT_STYLE,
    ) -> None:  # fmt: skip
        if scale <= 0:
            raise ValueError(f"scale must be positive, got {scale}")
        self.rows, self.cols = (int(n) for n in truth_shape)
        self.layers, self.scale, self.style = layers, float(scale), style
        self.map_size = (max(round(self.cols * scale), 1), max(round(self.rows * scale), 1))
        self.size = tuple(max(n + n % 2, 2) for n in self.map_size)  # (width, height), even
        self._to_px = np.array(self.map_size) / (self.cols, self.rows) * _ONE
        self._lut = style.lut(layers)
        self._table = packed_colours(self._lut)
        self._legend: tuple[tuple[str, ...], np.ndarray] | None = None
        # Scratch grids reused by every frame (fresh ones cost page faults at every frame).
        self._grids = LabelGrids((self.rows, self.cols))
        self._big = np.empty(self.map_size[::-1], dtype=np.uint8)

    def px(self, xy: Sequence[float] | np.ndarray) -> np.ndarray:
        """World (x, y) points -> fixed-point output pixel coordinates (int32, 4 bits)."""
        return np.round(np.asarray(xy, dtype=float) * self._to_px - _ONE / 2).astype(np.int32)

    def render(self, snapshot: Snapshot) -> np.ndarray:
        """The frame of ``snapshot``: (height, width, 3) uint8 BGR; the snapshot is not changed."""
        if snapshot.truth.shape != (self.rows, self.cols):
            raise ValueError(f"snapshot map {snapshot.truth.shape} != {(self.rows, self.cols)}")
        label = self._grids.labels(snapshot, self.layers, len(self.style.palette))
        image = self._colour(label)
        self._draw_vectors(image, snapshot)
        return image

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

    def _draw_vectors(self, image: np.ndarray, snap: Snapshot) -> None:
        """Everything drawn in output pixels, bottom to top."""
        on, style = self.layers.global_layers, self.style
        centres = self.px([a.position for a in snap.agents])
        colours = [style.base, *(style.robot_colour(i) for i in range(len(snap.robots)))]
        agents = list(zip(snap.agents, centres, colours, strict=True))
        self._draw_network(image, snap, centres, colours)
        for agent, _, colour in agents[1:]:
            self._draw_plans(image, agent, colour)
        if "location" in self.layers.for_agent(snap.base.name):
            c, half = centres[0], 5 * _ONE
            cv2.rectangle(image, c - half, c + half, style.base, -1, cv2.LINE_8, _SHIFT)
            draw_label(image, snap.base.name, centres[0], 5.0, style.base, style)
        for agent, c, colour in agents[1:]:
            if "location" in self.layers.for_agent(agent.name):
                size = max(style.robot_px, agent.radius * self.scale)
                draw_robot(image, agent, c, size, colour, style)
                draw_label(image, agent.name, c, size, colour, style)
        if "header" in on:
            draw_header(image, snap, style)
        if "legend" in on:
            self._paste_legend(image, tuple(r.name for r in snap.robots))

    def _draw_network(
        self, image: np.ndarray, snap: Snapshot, centres: np.ndarray, colours: list[BGR]
    ) -> None:
        """Comm range circles, communication links and hierarchy (parent) lines."""
        for agent, c, colour in zip(snap.agents, centres, colours, strict=True):
            if "comm_range" in self.layers.for_agent(agent.name) and agent.comm_range > 0:
                radius = round(agent.comm_range * self.scale * _ONE)
                cv2.circle(image, c, radius, colour, 1, _AA, _SHIFT)
        on, index = self.layers.global_layers, {a.name: i for i, a in enumerate(snap.agents)}
        ends = centres[np.argwhere(np.triu(snap.links, 1))] if "links" in on else []
        if len(ends):  # one call for all links: 1-pixel AA polylines draw as cv2.line does
            cv2.polylines(image, list(ends), False, self.style.link, 1, _AA, _SHIFT)
        if "hierarchy" in on:
            parents = [(i, index.get(a.parent)) for i, a in enumerate(snap.agents)]
            for i, j in ((i, j) for i, j in parents if j is not None):
                cv2.line(image, centres[i], centres[j], self.style.hierarchy, 2, _AA, _SHIFT)

    def _draw_plans(self, image: np.ndarray, robot: AgentSnapshot, colour: BGR) -> None:
        """A robot's path, goal and rendezvous points (each when its layer is on)."""
        mine = self.layers.for_agent(robot.name)
        if "path" in mine and len(robot.path):
            pts = self.px(np.vstack((robot.position, robot.path)))
            cv2.polylines(image, [pts], False, colour, 1, _AA, _SHIFT)
        if "goal" in mine and robot.goal is not None:
            draw_cross(image, self.px(robot.goal), 4, colour)
        points = robot.rendezvous
        if "rendezvous" in mine and points is not None and len(points):
            for p in self.px(np.reshape(points, (-1, 2))) >> _SHIFT:
                cv2.drawMarker(image, p, colour, cv2.MARKER_DIAMOND, 8, 2)

    def _paste_legend(self, image: np.ndarray, names: tuple[str, ...]) -> None:
        if self._legend is None or self._legend[0] != names:
            self._legend = (names, legend_band(image.shape[1], names, self.layers, self.style))
        band = self._legend[1][-image.shape[0] :]
        image[image.shape[0] - band.shape[0] :] = band


def draw_cross(image: np.ndarray, centre: np.ndarray, half: int, colour: BGR) -> None:
    """An 'x' of half-size ``half`` pixels at a fixed-point ``centre``."""
    for d in np.array(((1, 1), (1, -1)), dtype=np.int32) * half * _ONE:
        cv2.line(image, centre - d, centre + d, colour, 2, _AA, _SHIFT)


def draw_robot(
    image: np.ndarray, robot: AgentSnapshot, at: np.ndarray, size: float, colour: BGR, style: Style
) -> None:
    """A triangle: filled (active), red outline (error), hollow (done), grey + red X (failed)."""
    angles = robot.heading + np.array((0.0, 2.4, -2.4))
    reach = np.array((1.6, 1.0, 1.0))[:, None] * size * _ONE
    pts = (at + np.column_stack((np.cos(angles), np.sin(angles))) * reach).astype(np.int32)
    if robot.state == "done":
        cv2.polylines(image, [pts], True, colour, 2, _AA, _SHIFT)
        return
    cv2.fillPoly(image, [pts], style.failed if robot.state == "failed" else colour, _AA, _SHIFT)
    outline, width = (style.error, 2) if robot.state == "error" else ((0, 0, 0), 1)
    cv2.polylines(image, [pts], True, outline, width, _AA, _SHIFT)
    if robot.state == "failed":
        draw_cross(image, at, max(round(size * 0.8), 3), style.error)


def draw_label(
    image: np.ndarray, text: str, at: np.ndarray, offset: float, colour: BGR, style: Style
) -> None:
    """``text`` up and right of the fixed-point point ``at``, on a white halo."""
    x, y = (int(v) >> _SHIFT for v in at)
    org = (x + int(offset) + 2, y - int(offset) - 1)
    cv2.putText(image, text, org, _FONT, style.font_scale, (255, 255, 255), 3, _AA)
    cv2.putText(image, text, org, _FONT, style.font_scale, colour, 1, _AA)


def draw_header(image: np.ndarray, snap: Snapshot, style: Style) -> None:
    """Step, explored %, known at base % and alive robots, in a band at the top."""
    text = f"step {snap.step}   explored {snap.explored:.1%}   at base {snap.known_at_base:.1%}"
    text += f"   robots {snap.alive}/{len(snap.robots)}"
    (_, th), base = cv2.getTextSize(text, _FONT, style.font_scale, 1)
    cv2.rectangle(image, (0, 0), (image.shape[1], th + base + 5), style.header_bg, -1)
    cv2.putText(image, text, (4, th + 3), _FONT, style.font_scale, style.header_text, 1, _AA)


def legend_band(width: int, names: Sequence[str], layers: LayerSpec, style: Style) -> np.ndarray:
    """A band image with colour swatches for the map classes shown and every robot."""
    on = layers.global_layers
    items = [
        (name.replace("_", " "), getattr(style, name)) for key, name in _LEGEND.items() if key in on
    ]
    if "frontiers" in set(layers.robot_layers).union(*layers.per_robot.values()):
        items.append(("frontier", style.frontier))
    items += [(name, style.robot_colour(i)) for i, name in enumerate(names)]
    (_, th), base = cv2.getTextSize("Ag", _FONT, style.font_scale, 1)
    line, spots, x, y = th + base + 4, [], 4, 0
    for text, colour in items:
        w = cv2.getTextSize(text, _FONT, style.font_scale, 1)[0][0] + th + 12
        x, y = (4, y + line) if x + w > width and x > 4 else (x, y)
        spots.append((x, y, text, colour))
        x += w
    band = np.full((y + line + 2, width, 3), style.legend_bg, dtype=np.uint8)
    for x, y, text, colour in spots:
        cv2.rectangle(band, (x, y + 3), (x + th, y + 3 + th), colour, -1)
        cv2.rectangle(band, (x, y + 3), (x + th, y + 3 + th), (60, 60, 60), 1)
        org = (x + th + 4, y + 3 + th)
        cv2.putText(band, text, org, _FONT, style.font_scale, (0, 0, 0), 1, _AA)
    return band
