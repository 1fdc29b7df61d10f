"""Views (phase 8): a run snapshot as a BGR frame, with the layers the user picks.

Raster stage (``render_raster``), at grid resolution: a uint8 label per cell, class (0
unexplored, 1 team-known, 2 known at base, 3 wall, 4 skeleton, 5 frontier; the larger wins)
+ 6 * free/safe space tint (later robots over earlier), coloured by one lookup table and
resized once. Vector stage (``render_draw``), in output pixels with cv2 primitives: comm
ranges, links, hierarchy, paths, goals, rendezvous points, robots, names, header and legend.
On an 8-robot 800x600 office frame with every layer on, a new snapshot each frame costs
~2-3 ms (``benchmarks/bench_render.py``; the numpy/cv2 renderer it replaced took 6-8 ms).

Typical use: ``Renderer(truth.shape, parse_layers("all")).render(snapshot)``.
"""

from __future__ import annotations

import difflib
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import TYPE_CHECKING

import cv2
import numpy as np

from mresim_phys.render.draw import ONE, Overlay
from mresim_phys.render.raster import AT_BASE, CLASSES, LabelGrids, colour_labels, packed_colours
from mresim_phys.snapshot import Snapshot
from mresim_phys.types import FREE, OCCUPIED, UNKNOWN

if TYPE_CHECKING:
    from mresim_phys.comms.regions import RegionProbe

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
_AREA = cv2.INTER_AREA
_CLASS_COLOURS = ("team_known", "known_at_base", "wall", "skeleton", "frontier")  # classes 1-5
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
        self.size = tuple(max(n + n % 2, 2) for n in self.map_size)  # (width, height), even
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
