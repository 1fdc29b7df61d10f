"""Viewer (output edge), protocol: the messages between the page and the server.

The page sends JSON text messages over one WebSocket:

* ``{"op": "frame", "n": 12, "layers": L, "known": 40}``: the frame of logged step ``n``
  (a replay; live runs answer with their newest step) drawn with layers ``L``, and the
  timeline entries from index ``known`` on;
* ``{"op": "play"}``, ``"pause"``, ``"step"``, ``"stop"``, ``{"op": "speed", "value": 20}``:
  the live simulation's controls (a replay plays in the page).

``L`` is ``{"team": [global layers], "robots": {"A": [robot layers], ...}}``. The server
answers ``{"type": "info", ...}`` on connection (names, layers, frame size, mode, a
replay's step count and timeline), then for each frame a JSON header (``type: frame``, the
step, the agents' hover rows, new timeline entries, play state) followed by one binary
message: the PNG. ``{"type": "reload"}`` says the source changed (a live run ended and
its log is now replayed); ``{"type": "error"}`` answers a malformed message.

Bounds (:func:`decode`): a text message is at most :data:`MAX_MESSAGE` characters of JSON
nested at most :data:`MAX_DEPTH` deep, without ``NaN`` or ``Infinity``; anything else
is answered with an error message and changes nothing. A message of more than
:data:`MAX_FRAME` bytes closes the socket (WebSocket code 1009), as aiohttp does.
"""

from __future__ import annotations

import json
import math
import re
import reprlib
from dataclasses import dataclass
from typing import Any

from mresim_phys.render.layers import DEFAULT_ROBOT, GLOBAL_LAYERS, ROBOT_LAYERS, LayerSpec
from mresim_phys.render.style import DEFAULT_STYLE

OPS = ("frame", "play", "pause", "step", "stop", "speed")
MAX_SPEED = 10_000.0  # steps per second
MAX_MESSAGE = 1 << 18  # characters of a text message (a layer set for ~1000 agents)
MAX_FRAME = 1 << 20  # bytes of any WebSocket message; larger ones close the socket
MAX_DEPTH = 8  # nesting of a message's JSON (a frame request nests 4 deep)
STRINGS = re.compile(r'"(?:[^"\\]|\\.)*"', re.DOTALL)
BRACKETS = re.compile(r"[\[\]{}]")
SHOWN = reprlib.Repr()
SHOWN.maxstring = SHOWN.maxother = SHOWN.maxlong = 40


class ProtocolError(ValueError):
    """A message the page should not have sent (answered with an error message)."""


@dataclass(frozen=True)
class Message:
    """One checked message from the page."""

    op: str
    n: int = 0
    layers: LayerSpec | None = None
    known: int = 0
    value: float = 0.0


def too_deep(text: str, limit: int = MAX_DEPTH) -> bool:
    """Whether the arrays and objects of JSON ``text`` nest more than ``limit`` deep
    (brackets inside strings do not count)."""
    if text.count("[") + text.count("{") <= limit:
        return False
    depth = 0
    for bracket in BRACKETS.finditer(STRINGS.sub("", text)):
        depth += 1 if bracket.group() in "[{" else -1
        if depth > limit:
            return True
    return False


def finite(text: str) -> float:
    """A JSON number with a fraction or exponent; ProtocolError if it overflows to inf."""
    value = float(text)
    if not math.isfinite(value):
        raise ProtocolError(f"the number {text[:40]} is too large")
    return value


def not_a_number(text: str) -> float:
    """``NaN``, ``Infinity`` and ``-Infinity`` are not JSON: refused."""
    raise ProtocolError(f"{text} is not a JSON number")


def decode(text: str) -> Any:
    """A page's text message as JSON, within the bounds; ProtocolError if it is not."""
    if len(text) > MAX_MESSAGE:
        raise ProtocolError(
            f"a message is at most {MAX_MESSAGE} characters of JSON; this one has {len(text)}"
        )
    if too_deep(text):
        raise ProtocolError(f"a message's JSON nests at most {MAX_DEPTH} arrays or objects deep")
    try:
        return json.loads(text, parse_float=finite, parse_constant=not_a_number)
    except RecursionError:  # the depth check above should make this unreachable
        raise ProtocolError("a message's JSON nests too deep") from None
    except ProtocolError:
        raise
    except ValueError as exc:
        raise ProtocolError(f"a message must be JSON: {str(exc)[:100]}") from None


def layer_spec(data: Any, names: list[str]) -> LayerSpec:
    """The layer set of a page's ``layers`` object; ProtocolError if malformed."""
    if not isinstance(data, dict) or not isinstance(data.get("team", []), list):
        raise ProtocolError("layers must be {'team': [...], 'robots': {name: [...]}}")
    team = frozenset(str(v) for v in data.get("team", []))
    robots = data.get("robots", {})
    if not isinstance(robots, dict) or not all(isinstance(v, list) for v in robots.values()):
        raise ProtocolError("layers.robots must map agent names to lists of layers")
    unknown = sorted(set(robots) - set(names))
    if unknown:
        raise ProtocolError(f"layers.robots: no agent {SHOWN.repr(unknown[0])} in this run")
    per_robot = {str(k): frozenset(str(x) for x in v) for k, v in robots.items()}
    try:
        return LayerSpec(team, DEFAULT_ROBOT, per_robot)
    except ValueError as exc:
        raise ProtocolError(f"layers: {exc}") from None


def whole(data: dict[str, Any], key: str) -> int:
    """A non-negative integer field (0 if absent)."""
    value = data.get(key, 0)
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise ProtocolError(f"{key!r} must be a whole number >= 0, not {SHOWN.repr(value)}")
    return value


def parse_message(data: Any, names: list[str]) -> Message:
    """Check one decoded JSON message from the page."""
    if not isinstance(data, dict) or data.get("op") not in OPS:
        raise ProtocolError(f"a message needs 'op', one of {', '.join(OPS)}")
    op = str(data["op"])
    if op == "frame":
        return Message(
            op, whole(data, "n"), layer_spec(data.get("layers"), names), whole(data, "known")
        )
    if op == "speed":
        value = data.get("value")
        if (
            isinstance(value, bool)
            or not isinstance(value, int | float)
            or not 0 <= value <= MAX_SPEED
        ):
            raise ProtocolError(f"speed must be 0 (as fast as it goes) to {MAX_SPEED:g} steps/s")
        return Message(op, value=float(value))
    return Message(op)


def layers_json(layers: LayerSpec, names: list[str]) -> dict[str, Any]:
    """A layer set as the page holds it (every agent listed)."""
    return {
        "team": [name for name in GLOBAL_LAYERS if name in layers.global_layers],
        "robots": {n: [x for x in ROBOT_LAYERS if x in layers.for_agent(n)] for n in names},
    }


def agent_colours(kinds: list[str]) -> list[str]:
    """Each agent's colour in frames, as ``#rrggbb``: the base's, then the robots' in order
    (``render/draw.py``)."""
    out, robots = [], 0
    for kind in kinds:
        b, g, r = DEFAULT_STYLE.base if kind != "robot" else DEFAULT_STYLE.robot_colour(robots)
        robots += kind == "robot"
        out.append(f"#{r:02x}{g:02x}{b:02x}")
    return out


def info_message(
    mode: str,
    names: list[str],
    kinds: list[str],
    layers: LayerSpec,
    size: tuple[int, int],
    extra: dict[str, Any],
) -> dict[str, Any]:
    """The first message a page receives."""
    return {
        "type": "info",
        "mode": mode,
        "names": names,
        "kinds": kinds,
        "colours": agent_colours(kinds),
        "global_layers": list(GLOBAL_LAYERS),
        "robot_layers": list(ROBOT_LAYERS),
        "layers": layers_json(layers, names),
        "size": list(size),
        **extra,
    }
