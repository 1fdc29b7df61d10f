"""Viewer (output edge), frames: a snapshot drawn as the browser shows it.

A :class:`FrameMaker` renders a snapshot with the layers a page asks for through the same
:class:`~mresim_phys.render.Renderer` (same scale, style and communication regions) as a
run's video, and encodes it as PNG (lossless: the page's pixels are the renderer's).
:func:`agent_rows` gives what hovering a robot shows (state, activity: working, waiting,
idle or stuck, role, distance travelled, path left: from the believed position with
localisation, battery, last contact with the base, each feature's hover entry: the
believed pose with localisation; in a run whose strategies plan meetings, the meetings
pending for it) and where the robot is in frame pixels. Typical use:
``FrameMaker(shape, scale).png(snapshot, layers)``.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from collections.abc import Callable
from typing import Any

import cv2
import numpy as np

from mresim_phys.comms.regions import RegionProbe
from mresim_phys.features import FEATURES
from mresim_phys.meeting_board import pending_of
from mresim_phys.render import LayerSpec, Renderer, frame_scale
from mresim_phys.render.pose import path_start
from mresim_phys.snapshot import AgentSnapshot, Snapshot

RENDERERS_KEPT = 8  # renderers of different layer sets kept (each holds scratch grids)
PNG_LEVEL = 1  # zlib level of the frames sent: fast, and still lossless

RegionsFor = Callable[[Snapshot], RegionProbe | None]


def no_regions(snapshot: Snapshot) -> RegionProbe | None:
    """Communication ranges drawn as circles."""
    return None


class FrameMaker:
    """Render snapshots of one run for the page, one renderer per layer set (one thread).

    Args:
        shape: (rows, cols) of the map.
        scale: The run's ``render.scale`` (the frame scale is ``frame_scale`` of it, as
            for the run's video).
        regions: Gives the communication-region probe to draw a snapshot with (as the
            run's video: polygons through the walls, or None for circles).
    """

    def __init__(
        self, shape: tuple[int, int], scale: float, regions: RegionsFor = no_regions
    ) -> None:
        self.shape, self.scale = shape, frame_scale(shape, scale)
        self.regions = regions
        self._renderers: OrderedDict[LayerSpec, Renderer] = OrderedDict()

    def renderer(self, layers: LayerSpec) -> Renderer:
        """The renderer of ``layers`` (built once, the least recently used dropped)."""
        renderer = self._renderers.pop(layers, None)
        if renderer is None:
            renderer = Renderer(self.shape, layers, self.scale)
        self._renderers[layers] = renderer
        while len(self._renderers) > RENDERERS_KEPT:
            self._renderers.popitem(last=False)
        return renderer

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) of every frame in pixels."""
        return self.renderer(LayerSpec()).size

    def frame(self, snapshot: Snapshot, layers: LayerSpec) -> np.ndarray:
        """The BGR frame of ``snapshot`` with ``layers``, exactly as the video draws it."""
        renderer = self.renderer(layers)
        renderer.regions = self.regions(snapshot)
        return renderer.render(snapshot)

    def png(self, snapshot: Snapshot, layers: LayerSpec) -> bytes:
        """The frame as PNG bytes."""
        return encode_png(self.frame(snapshot, layers))

    def agents(self, snapshot: Snapshot) -> list[dict[str, Any]]:
        """Hover rows of the snapshot's agents (see :func:`agent_rows`)."""
        return agent_rows(snapshot, self.renderer(LayerSpec()))


def encode_png(frame: np.ndarray) -> bytes:
    """A BGR frame as PNG bytes (RGB on decoding, no gamma chunk: sRGB as drawn)."""
    ok, data = cv2.imencode(".png", frame, [cv2.IMWRITE_PNG_COMPRESSION, PNG_LEVEL])
    if not ok:
        raise ValueError(f"OpenCV could not encode a {frame.shape} frame as PNG")
    return data.tobytes()


def path_length(points: np.ndarray) -> float:
    """Length of a polyline of (k, 2) points (0 for fewer than two)."""
    if len(points) < 2:
        return 0.0
    return float(np.hypot(*np.diff(points, axis=0).T).sum())


def agent_rows(snapshot: Snapshot, renderer: Renderer) -> list[dict[str, Any]]:
    """What hovering each agent shows, and its place (``px``, ``r``) in frame pixels."""
    positions = np.array([a.position for a in snapshot.agents], dtype=float)
    centres = renderer.px(positions) / 16.0 + 0.5  # pixel centres -> canvas coordinates
    per_cell = renderer.map_size[0] / renderer.cols
    return [
        agent_row(agent, (float(x), float(y)), agent.radius * per_cell)
        | meetings_entry(snapshot, agent)
        for agent, (x, y) in zip(snapshot.agents, centres, strict=True)
    ]


def meetings_entry(snapshot: Snapshot, agent: AgentSnapshot) -> dict[str, Any]:
    """The meetings pending for ``agent`` (``meeting_board.py``), in a run with meetings."""
    board = snapshot.meetings
    return {} if board is None else {"meetings": pending_of(board, agent.name)}


def feature_entries(agent: AgentSnapshot) -> dict[str, Any]:
    """Each feature's hover entry (None where the agent has no such feature)."""
    values = agent.features
    return {f.key: f.hover(values[f.key]) if f.key in values else None for f in FEATURES.recorded()}


def agent_row(agent: AgentSnapshot, px: tuple[float, float], radius: float) -> dict[str, Any]:
    """One agent's hover row (JSON-ready; distances in cells; the path left from where the
    path is drawn from: the believed position with localisation)."""
    start = np.array([path_start(agent)], dtype=float)
    return {
        "name": agent.name,
        "kind": agent.kind,
        "px": [round(px[0], 2), round(px[1], 2)],
        "r": round(max(radius, 3.0), 2),
        "state": agent.state,
        "role": agent.role,
        "distance": round(agent.distance, 2),
        "path_left": round(path_length(np.concatenate([start, agent.path])), 2),
        **feature_entries(agent),
        "base_contact": agent.base_contact,
        "position": [round(v, 2) for v in agent.position],
        "heading_deg": round(math.degrees(agent.heading), 1),
    }
