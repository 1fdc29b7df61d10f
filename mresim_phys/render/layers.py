"""Views (phase 8), layers: what a frame may show, and the ``--layers`` mini-language.

Global layers (map classes; moving obstacles, doors and debris of a changing world;
links, hierarchy, legend, header, terrain shading, a prior map's walls, the knowledge lost
at failures, hazard zones, a scale bar, meetings kept and missed) and per-robot layers
(location, path, goal, free and safe space, frontiers, comm range, skeleton, rendezvous:
the agreed points, the potential ones and those linked through walls, the teammates it
presumes lost, its believed pose with localisation);
a :class:`LayerSpec` says which are on, for all robots and for named ones;
:func:`parse_layers` reads the ``--layers`` / ``render.layers`` text.

Typical use: ``parse_layers("default,B:free_space").for_agent("B")``.
"""

from __future__ import annotations

import difflib
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType

GLOBAL_LAYERS: tuple[str, ...] = ("walls", "unexplored", "team_known", "known_at_base")
GLOBAL_LAYERS += ("obstacles", "doors", "debris")  # a changing world: drawn over the walls
GLOBAL_LAYERS += ("links", "hierarchy", "legend", "header", "terrain", "prior")
GLOBAL_LAYERS += ("lost_knowledge",)  # cells only a robot that fell silent knew
GLOBAL_LAYERS += ("hazards",)  # hazard zones of a faults: block
GLOBAL_LAYERS += ("scale_bar",)  # metres on the frame, when the map's resolution is known
GLOBAL_LAYERS += ("meetings",)  # meetings kept and missed (the rendezvous accounting)
GLOBAL_LAYERS += ("ground",)  # ground classes, each shaded in its colour (ground/)
ROBOT_LAYERS: tuple[str, ...] = ("location", "path", "free_space", "safe_space", "frontiers")
ROBOT_LAYERS += ("comm_range", "goal", "skeleton", "rendezvous", "presumed_lost")
ROBOT_LAYERS += ("rv_candidates", "rv_through_walls")  # multi-point rendezvous
ROBOT_LAYERS += ("localization",)  # a robot's believed pose and its 95 % ellipse
ROBOT_LAYERS += ("radio",)  # bytes queued on bounded links, beside the robot's name
ROBOT_LAYERS += ("ghost_walls",)  # cells an agent's map holds as walls that are free
ROBOT_LAYERS += ("readings",)  # a beam-model laser's share of noisy readings, by the name
ROBOT_LAYERS += ("clock",)  # a clocked robot's decisions and its plan's wait, by the name
LAYERS = GLOBAL_LAYERS + ROBOT_LAYERS
DEFAULT_GLOBAL = frozenset(GLOBAL_LAYERS)
DEFAULT_ROBOT = frozenset(ROBOT_LAYERS) - {
    "free_space",
    "safe_space",
    "rv_candidates",
    "ghost_walls",
}
DEFAULTS = DEFAULT_GLOBAL | DEFAULT_ROBOT
_KINDS = f"global layers: {', '.join(GLOBAL_LAYERS)}; robot layers: {', '.join(ROBOT_LAYERS)}"


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
    robot = chosen & set(ROBOT_LAYERS)
    per_robot: dict[str, frozenset[str]] = {}
    for token in (t for t in tokens if ":" in t):
        name, _, rest = token.partition(":")
        if not name or not re.fullmatch(r"[+-]?\w+([+-]\w+)*", rest):
            raise ValueError(f"layers: {token!r} should look like 'B:free_space+path-goal'")
        changes = re.findall(r"([+-]?)(\w+)", rest)
        per_robot[name] = frozenset(_apply(set(per_robot.get(name, robot)), changes, ROBOT_LAYERS))
    return LayerSpec(frozenset(chosen & set(GLOBAL_LAYERS)), frozenset(robot), per_robot)
