"""Run log meta.json (output edge): the static data of a run log, read back and checked.

``meta.json`` (docs/run-log-format.md) is a run log's commit point: format, version,
name, seed, grid shape, chunk size, the agents' static table, the robots' starts and the
committed step count, (version 3) the moving obstacles and doors (``output.logworld``)
and (version 5) what the explorable area was computed from (``sights``:
:func:`sight_meta`, :func:`read_sights`). :func:`read_meta` reads it and checks every
value, so a damaged or foreign file is a MresimError naming it rather than an error deep
in a replay.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from mresim_phys.errors import MresimError
from mresim_phys.output.logformat import FORMAT, READABLE, STATIC_AGENT, decode_line
from mresim_phys.output.logworld import read_movable_meta
from mresim_phys.snapshot import AgentSnapshot
from mresim_phys.types import RobotSight

META = "meta.json"


def damaged(log_dir: Path, what: str) -> MresimError:
    """The error for an unreadable log."""
    return MresimError(f"{log_dir}: the run log is damaged ({what}); re-run to write a new one.")


def read_meta(log_dir: Path) -> dict[str, Any]:
    """meta.json, checked for format, version and required keys."""
    try:
        meta = json.loads((log_dir / META).read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise damaged(log_dir, f"{META}: {exc}") from None
    if not isinstance(meta, dict) or meta.get("format") != FORMAT:
        raise damaged(log_dir, f"{META} is not a {FORMAT} file")
    if meta.get("version") not in READABLE:
        versions = " and ".join(map(str, READABLE))
        raise MresimError(
            f"{log_dir}: run log format version {meta.get('version')!r}; this mresim reads"
            f" versions {versions}. Re-run the scenario or use a matching mresim."
        )
    missing = {"name", "seed", "shape", "chunk_steps", "agents", "starts", "steps"} - meta.keys()
    if missing:
        raise damaged(log_dir, f"{META} lacks {sorted(missing)}")
    problem = meta_problem(meta)
    if problem is not None:
        raise damaged(log_dir, f"{META}: {problem}")
    return meta


def whole(value: Any, least: int) -> bool:
    """Whether ``value`` is an integer (not a bool) >= ``least``."""
    return isinstance(value, int) and not isinstance(value, bool) and value >= least


def positive(value: Any) -> bool:
    """Whether ``value`` is a finite number (not a bool) > 0."""
    number = isinstance(value, int | float) and not isinstance(value, bool)
    return number and math.isfinite(value) and value > 0


def is_point(value: Any) -> bool:
    """Whether ``value`` is an ``[x, y]`` pair of numbers."""
    return (
        isinstance(value, list)
        and len(value) == 2
        and all(isinstance(v, int | float) and not isinstance(v, bool) for v in value)
    )


def meta_problem(meta: dict[str, Any]) -> str | None:
    """What is wrong with the values of a meta.json that has every key (None: nothing)."""
    shape, agents, starts = meta["shape"], meta["agents"], meta["starts"]
    if not (isinstance(shape, list) and len(shape) == 2 and all(whole(v, 1) for v in shape)):
        return f"shape {shape!r} is not [rows, columns]"
    for key, least in (("chunk_steps", 1), ("steps", 0), ("seed", 0)):
        if not whole(meta[key], least):
            return f"{key} {meta[key]!r} is not a whole number >= {least}"
    if not isinstance(meta["name"], str):
        return f"name {meta['name']!r} is not a text"
    for key in ("resolution", "dt"):  # metres per cell, seconds per step: optional
        value = meta.get(key)
        if value is not None and not positive(value):
            return f"{key} {value!r} is not a positive number"
    if not isinstance(agents, list) or not agents:
        return f"agents {agents!r} is not a list of agents"
    for agent in agents:
        try:
            decode_line(STATIC_AGENT, AgentSnapshot, agent, len(agents))
        except (AttributeError, KeyError, TypeError, ValueError):
            return f"agent {agent!r} lacks a name, kind, radius or comm_range"
    robots = sum(1 for a in agents if a["kind"] == "robot")
    if not (isinstance(starts, list) and len(starts) == robots and all(map(is_point, starts))):
        return f"starts {starts!r} are not {robots} [x, y] points"
    return movables_problem(meta.get("movables", [])) or sights_problem(meta, robots)


def sight_meta(sight: RobotSight) -> dict[str, Any]:
    """One robot's entry of meta.json's ``sights``."""
    seeds = [[int(r), int(c)] for r, c in sight.seeds or ()]
    return {
        "start": [float(sight.start[0]), float(sight.start[1])],
        "radius": float(sight.radius),
        "range": float(sight.sensor_range),
        "seeds": seeds,
    }


def read_sights(meta: dict[str, Any]) -> tuple[RobotSight, ...]:
    """meta.json's ``sights`` read back (checked by :func:`read_meta`; (): none, a log
    older than version 5 or one written from hand-made snapshots)."""
    return tuple(
        RobotSight(
            (float(e["start"][0]), float(e["start"][1])),
            float(e["radius"]),
            float(e["range"]),
            tuple((int(r), int(c)) for r, c in e["seeds"]),
        )
        for e in meta.get("sights", [])
    )


def sights_problem(meta: dict[str, Any], robots: int) -> str | None:
    """What is wrong with meta.json's ``sights`` (None: nothing, or no such key)."""
    sights = meta.get("sights", [])
    if not isinstance(sights, list) or len(sights) not in (0, robots):
        return f"sights {sights!r} is not a list of {robots} robots' sights"
    rows, cols = meta["shape"]
    for entry in sights:
        try:
            sight = read_sights({"sights": [entry]})[0]
        except (IndexError, KeyError, TypeError, ValueError):
            return f"sight {entry!r} lacks a start, radius, range or seeds"
        inside = all(0 <= r < rows and 0 <= c < cols for r, c in sight.seeds or ())
        if not (is_point(entry["start"]) and inside and sight.radius > 0 <= sight.sensor_range):
            return f"sight {entry!r} has a seed outside the map, no radius or a negative range"
    return None


def movables_problem(movables: Any) -> str | None:
    """What is wrong with meta.json's ``movables`` list (absent before version 3)."""
    if not isinstance(movables, list):
        return f"movables {movables!r} is not a list"
    for entry in movables:
        try:
            read_movable_meta(entry)
        except (IndexError, KeyError, TypeError, ValueError):
            return f"movable {entry!r} lacks a name, kind, shape or cells"
    return None
