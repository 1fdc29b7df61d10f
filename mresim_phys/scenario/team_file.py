"""Scenario input (phase 0): the original MRESim's robot team files, read into our scenario YAML.

The original keeps a team in a whitespace-separated text file, one agent per line, 11
columns, the base station first (``config/8robots_library``, ``config/4robots_rooms``,
...): number, name, start x and y (pixels of the 800x600 map), heading (radians, y
down), sensing range, comm range, battery life (unused), role (``BaseStation``,
``Explorer``, ``Relay``), parent number, child number. :func:`read_team_file` turns it
into a scenario mapping (``mresim import-team``): the base station and its comm range,
one robot per line with its start, heading, laser range and comm range, its role, and
its parent where the team has a hierarchy (a relay's parent, and the parent of an
explorer paired with a relay; the greedy files' "parent 1" of every explorer is not a
hierarchy and is dropped). The original's other settings become the team defaults:
speed 10, laser 180 degrees / 181 rays, the body our comparisons use (radius 0.5,
wall margin 0.5; ``docs/differences-from-original.md``) and its radio model, PropModel1
(``path_loss`` with its defaults). Agents stand on the centres of the original's pixels.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from mresim_phys.errors import MresimError
from mresim_phys.scenario.yamlfile import require_file

COLUMNS = 11
ORIGINAL_COMM = "path_loss"  # PropModel1, the default of the original's lastSimulatorConfig
MAX_TEAM_BYTES = 1_000_000  # ~10,000 agents
ROLES = {"basestation": "base", "explorer": "explorer", "relay": "relay"}
ORIGINAL_TEAM: dict[str, Any] = {
    "speed": 10,
    "radius": 0.5,
    "wall_margin": 0.5,
    "sensor": {"fov_deg": 180, "rays": 181},
}


def read_team_file(
    path: Path, map_image: str, strategy: str = "frontier", comm: str = ORIGINAL_COMM
) -> dict[str, Any]:
    """The scenario mapping of the team in ``path`` on ``map_image``; MresimError naming the
    file and line when a line does not follow the original's format."""
    require_file(path, "Team file", MresimError)
    try:
        if path.stat().st_size > MAX_TEAM_BYTES:
            raise MresimError(
                f"Team file {path} is {path.stat().st_size:,} bytes; the original's team files"
                f" are a line per agent (at most {MAX_TEAM_BYTES:,} bytes here). Is it the"
                " right file?"
            )
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise MresimError(f"{path}: cannot read the team file ({exc.strerror or exc})") from None
    rows = [parse_line(path, n, line) for n, line in enumerate(text.splitlines(), 1)]
    agents = [row for row in rows if row is not None]
    if not agents or agents[0]["role"] != "base":
        raise MresimError(
            f"{path}: the first agent line must be the base station (role BaseStation), as in"
            " the original's team files"
        )
    return scenario_of(path, agents, map_image, strategy, comm)


def parse_line(path: Path, number: int, line: str) -> dict[str, Any] | None:
    """One agent of the team file (None for a blank line)."""
    fields = line.split()
    if not fields:
        return None
    where = f"{path}, line {number}"
    if len(fields) != COLUMNS:
        raise MresimError(
            f"{where}: {len(fields)} columns, the original's team files have {COLUMNS} (number,"
            " name, x, y, heading, sensing range, comm range, battery, role, parent, child)"
        )
    role = ROLES.get(fields[8].lower())
    if role is None:
        raise MresimError(
            f"{where}: role {fields[8]!r} is none of BaseStation, Explorer, Relay (column 9)"
        )
    try:
        number_, x, y, heading = (
            int(fields[0]),
            float(fields[2]),
            float(fields[3]),
            float(fields[4]),
        )
        sense, comm, parent = float(fields[5]), float(fields[6]), int(fields[9])
    except ValueError as exc:
        raise MresimError(f"{where}: {exc} (columns 1, 3-8, 10 and 11 are numbers)") from None
    if not all(math.isfinite(v) for v in (x, y, heading, sense, comm)) or sense < 0 or comm < 0:
        raise MresimError(f"{where}: positions, heading and ranges must be finite, ranges >= 0")
    return {"number": number_, "name": fields[1], "x": x, "y": y, "heading": heading,
            "sense": sense, "comm": comm, "role": role, "parent": parent}  # fmt: skip


def cell_centre(agent: dict[str, Any]) -> list[float]:
    """The centre of the pixel the original places the agent on: pixel (x, y) spans
    [x, x + 1) x [y, y + 1) in our continuous frame, as scenarios 11-13 place them."""
    return [agent["x"] + 0.5, agent["y"] + 0.5]


def scenario_of(
    path: Path, agents: list[dict[str, Any]], map_image: str, strategy: str, comm: str
) -> dict[str, Any]:
    """The scenario mapping of parsed agents (the base first)."""
    base, robots = agents[0], agents[1:]
    names = {a["number"]: ("base" if a is base else a["name"]) for a in agents}
    hierarchy = any(r["role"] == "relay" for r in robots)
    entries = []
    for robot in robots:
        entry: dict[str, Any] = {
            "name": robot["name"],
            "start": cell_centre(robot),
            "heading_deg": round(math.degrees(robot["heading"]), 6),
            "sensor": {"range": robot["sense"]},
            "comm_range": robot["comm"],
            "role": robot["role"],
        }
        if hierarchy and robot["parent"] in names and robot["parent"] != robot["number"]:
            entry["parent"] = names[robot["parent"]]
        entries.append(entry)
    return {
        "name": path.stem.replace(" ", "_")[:64] or "team",
        "map": {"image": map_image},
        "base_station": {"position": cell_centre(base), "comm_range": base["comm"]},
        "team": {**ORIGINAL_TEAM, "strategy": strategy},
        "robots": entries,
        "communication": {"model": comm},
    }
