"""Scenario units and the map frame (phase 0, input): metres and seconds to cells and steps.

A scenario is in cells and steps unless it says ``units: m``. Then every position, length,
speed and region the schema gives in cells is read in metres and metres per second, and
positions are points of the *map frame*, as ROS and RViz place them: x to the right, y up,
from the map's ``origin`` (a ROS map's ``origin: [x, y, yaw]``, the pose of the lower-left
corner of the lower-left pixel; for an image map with ``map.resolution`` the origin is that
corner, at (0, 0)). A step lasts ``dt`` seconds; speeds in metres per second need it.
Step counts (``steps``, event ``step``, ``stop``) stay steps. Headings turn the ROS way:
counter-clockwise from +x, with y up.

:func:`to_cells` converts the scenario's mapping before it is validated, so the schema and
everything after it see cells only and a scenario in cells runs exactly as before. Its
checks raise :class:`ScenarioError` (one paragraph naming the file and the field; exit 2):
metres without a resolution, speeds without ``dt``, a rotated origin, a start or base
off the map. Plugin ``params`` (a strategy's ``reach``, a comm model's distances) keep their
own units, cells unless the plugin says otherwise.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from mresim_phys.errors import ScenarioError
from mresim_phys.scenario.frame import Converter, MapFrame, mapping, number, pair


def robot(data: Any, conv: Converter, where: str) -> Any:
    """A robot entry (or the team's defaults) in cells."""
    entry = mapping(data)
    if entry is None:
        return data
    out = dict(entry)
    for key in ("radius", "comm_range", "wall_margin"):
        if key in out:
            out[key] = conv.length(out[key])
    if "speed" in out:
        out["speed"] = conv.speed(out["speed"], f"{where}.speed")
    if "start" in out:
        out["start"] = conv.point(out["start"])
    if "heading_deg" in out:
        out["heading_deg"] = conv.heading(out["heading_deg"])
    sensor = mapping(out.get("sensor"))
    if sensor is not None:
        out["sensor"] = {
            k: conv.length(v) if k in ("range", "noise_std") else v for k, v in sensor.items()
        }
        beam = mapping(sensor.get("beam"))
        if beam is not None:
            out["sensor"]["beam"] = beam_in_cells(beam, conv)
    if mapping(out.get("localization")) is not None:
        out["localization"] = localization(out["localization"], conv)
    return out


def beam_in_cells(beam: dict[str, Any], conv: Converter) -> dict[str, Any]:
    """A sensor's ``beam`` block: its lengths (``sigma_hit``, ``max_free``, ``speckle``) in
    cells, the short returns' rate per cell."""
    out = dict(beam)
    for key in ("sigma_hit", "max_free", "speckle"):
        if key in out:
            out[key] = conv.length(out[key])
    if "lambda_short" in out:
        out["lambda_short"] = conv.per_length(out["lambda_short"])
    return out


LENGTHS = ("within", "range", "sigma", "sigma_range", "window")  # a correction's lengths


def localization(data: dict[str, Any], conv: Converter) -> dict[str, Any]:
    """A robot's ``localization`` block: the alphas a2 (rad^2 per m^2) and a4 (m^2 per
    rad^2) per cell, each correction's lengths and beacon positions in cells."""
    out = dict(data)
    odometry = mapping(out.get("odometry"))
    alpha = odometry.get("alpha") if odometry is not None else None
    if odometry is not None and isinstance(alpha, list) and len(alpha) == 4:
        a1, a2, a3, a4 = alpha
        scaled = [a1, conv.per_length(conv.per_length(a2)), a3, conv.length(conv.length(a4))]
        out["odometry"] = {**odometry, "alpha": scaled}
    if isinstance(out.get("corrections"), list):
        out["corrections"] = [_correction(c, conv) for c in out["corrections"]]
    return out


def _correction(data: Any, conv: Converter) -> Any:
    """One correction's lengths and points in cells."""
    entry = mapping(data)
    if entry is None:
        return data
    out = {k: conv.length(v) if k in LENGTHS else v for k, v in entry.items()}
    if isinstance(out.get("positions"), list):
        out["positions"] = [conv.point(p) for p in out["positions"]]
    return out


def obstacle(data: Any, conv: Converter, where: str) -> Any:
    """A moving obstacle: its shape, its path's points and its speed."""
    entry = mapping(data)
    if entry is None:
        return data
    out = dict(entry)
    out["shape"] = conv.shape(out.get("shape"))
    motion = mapping(out.get("motion"))
    if motion is not None:
        moved = dict(motion)
        if isinstance(moved.get("waypoints"), list):
            moved["waypoints"] = [conv.point(p) for p in moved["waypoints"]]
        for key in ("random_walk", "still"):
            if key in moved:
                moved[key] = conv.point(moved[key])
        if "speed" in moved:
            moved["speed"] = conv.speed(moved["speed"], f"{where}.motion.speed")
        out["motion"] = moved
    return out


def door(data: Any, conv: Converter) -> Any:
    """A door: its two ends and its leaf's thickness."""
    entry = mapping(data)
    if entry is None:
        return data
    out = dict(entry)
    if isinstance(out.get("between"), list):
        out["between"] = [conv.point(p) for p in out["between"]]
    if "thickness" in out:
        out["thickness"] = conv.length(out["thickness"])
    return out


def event(data: Any, conv: Converter) -> Any:
    """An event: a collapse's region or a cells window (others have no lengths)."""
    entry = mapping(data)
    if entry is None:
        return data
    out = dict(entry)
    if "collapse" in out:
        out["collapse"] = conv.region(out["collapse"])
    if "cells" in out:
        out["cells"] = conv.window(out["cells"])
    return out


def present(out: dict[str, Any], given: dict[str, Any]) -> dict[str, Any]:
    """``out`` without the keys a conversion added as None (the scenario left them out)."""
    return {k: v for k, v in out.items() if v is not None or k in given}


def listed(value: Any, convert: Callable[[Any, int], Any]) -> Any:
    """Each entry of a list converted (``convert(entry, index)``)."""
    return [convert(v, i) for i, v in enumerate(value)] if isinstance(value, list) else value


def faults(data: Any, conv: Converter) -> Any:
    """Hazard zones and the battery's charge per metre."""
    entry = mapping(data)
    if entry is None:
        return data
    out = dict(entry)
    out["hazards"] = listed(out.get("hazards"), lambda h, _: region_of(h, conv))
    battery = mapping(out.get("battery"))
    if battery is not None and "per_cell" in battery:
        out["battery"] = {**battery, "per_cell": conv.per_length(battery["per_cell"])}
    return present(out, entry)


def region_of(data: Any, conv: Converter) -> Any:
    """An entry whose ``region`` is converted."""
    entry = mapping(data)
    if entry is None or "region" not in entry:
        return data
    return {**entry, "region": conv.region(entry["region"])}


def world(data: dict[str, Any], conv: Converter) -> dict[str, Any]:
    """Obstacles, doors, events, debris, terrain, ground classes and faults in cells."""
    out = dict(data)
    out["obstacles"] = listed(
        out.get("obstacles"), lambda o, i: obstacle(o, conv, f"obstacles[{i}]")
    )
    out["doors"] = listed(out.get("doors"), lambda d, _: door(d, conv))
    out["events"] = listed(out.get("events"), lambda e, _: event(e, conv))
    debris = mapping(out.get("random_debris"))
    if debris is not None:
        debris = region_of(debris, conv)
        if isinstance(debris.get("size"), list):
            debris = {**debris, "size": [conv.cells(v) for v in debris["size"]]}
        out["random_debris"] = debris
    for key in ("terrain", "ground"):  # their regions' shapes
        layer = mapping(out.get(key))
        if layer is not None:
            out[key] = {
                **layer,
                "regions": listed(layer.get("regions"), lambda r, _: conv.region(r)),
            }
    out["faults"] = faults(out.get("faults"), conv)
    return present(out, data)


def agents(data: dict[str, Any], conv: Converter) -> dict[str, Any]:
    """The team, the robots, the base station, the control channel and the start jitter."""
    out = dict(data)
    out["team"] = robot(out.get("team"), conv, "team")
    out["robots"] = listed(out.get("robots"), lambda r, i: robot(r, conv, f"robots[{i}]"))
    base = mapping(out.get("base_station"))
    if base is not None:
        base = {**base, "position": conv.point(base.get("position"))}
        if "comm_range" in base:
            base["comm_range"] = conv.length(base["comm_range"])
        out["base_station"] = present(base, data["base_station"])
    comm = mapping(out.get("communication"))
    control = mapping(comm.get("control")) if comm is not None else None
    if comm is not None and control is not None and "range" in control:
        out["communication"] = {
            **comm,
            "control": {**control, "range": conv.length(control["range"])},
        }
    simulation = mapping(out.get("simulation"))
    jitter = mapping(simulation.get("start_jitter")) if simulation is not None else None
    if simulation is not None and jitter is not None and "position" in jitter:
        moved = {**jitter, "position": conv.length(jitter["position"])}
        out["simulation"] = {**simulation, "start_jitter": moved}
    return present(out, data)


def to_cells(data: dict[str, Any], source: str, folder: Path) -> dict[str, Any]:
    """The scenario mapping in cells: converted from metres and seconds when it says
    ``units: m`` (its ``units`` then reads ``cells``), else as it is."""
    if data.get("units") != "m":
        return data
    dt: Any = data.get("dt")
    if not (number(dt) and dt > 0):
        raise ScenarioError(
            f"{source}: units: m gives speeds in metres per second and a run in seconds, so it"
            f" needs the step duration: give 'dt' as a positive number of seconds per step"
            f" (e.g. dt: 0.1){'' if dt is None else f'; found dt: {dt!r}'}."
        )
    frame = map_frame(data.get("map"), source, folder)
    if frame is None:  # the map entry itself is wrong: the schema says how
        return data
    conv = Converter(frame, float(dt), source)
    out = world(agents(data, conv), conv)
    check_on_map(out, frame, data, source)
    return {**out, "units": "cells"}


def map_frame(raw: Any, source: str, folder: Path) -> MapFrame | None:
    """The map frame of the scenario's ``map`` entry (None when the entry is invalid)."""
    from pydantic import ValidationError

    from mresim_phys.scenario.maps import MapSpec
    from mresim_phys.scenario.readers import load_map

    try:
        spec = MapSpec.model_validate(raw)
    except ValidationError:
        return None
    kind, value = spec.source
    path = folder / Path(value).expanduser()
    if not path.is_file():  # the run's map check names the field and the path
        return None
    loaded = load_map(path, spec.threshold, spec.negate, spec.max_cells)
    resolution = loaded.resolution or spec.resolution
    if resolution is None:
        raise ScenarioError(
            f"{source}: units: m needs the map's size in metres, and map.{kind} ({value}) does"
            " not give it: add 'resolution' (metres per cell) to the map entry, or give the"
            " scenario in cells (remove 'units: m')."
        )
    x, y, yaw = loaded.origin or (0.0, 0.0, 0.0)
    if yaw != 0:
        raise ScenarioError(
            f"{source}: units: m places positions in the map frame, and map.{kind} ({value})"
            f" has a rotated origin (yaw {yaw:g} rad); rotated map frames are not supported:"
            " give the scenario in cells, or set the map's origin yaw to 0."
        )
    rows, cols = loaded.occupied.shape
    return MapFrame(rows, cols, float(resolution), (x, y))


def check_on_map(out: dict[str, Any], frame: MapFrame, given: dict[str, Any], source: str) -> None:
    """ScenarioError naming the first start or base position that the conversion puts off
    the map: an origin or unit mix-up."""
    places = [("base_station.position", mapping(out.get("base_station")) or {}, "position",
               mapping(given.get("base_station")) or {})]  # fmt: skip
    robots, raw = out.get("robots"), given.get("robots")
    if isinstance(robots, list) and isinstance(raw, list):
        places += [
            (f"robots[{i}].start", r, "start", g)
            for i, (r, g) in enumerate(zip(robots, raw, strict=False))
            if isinstance(r, dict) and isinstance(g, dict)
        ]
    for where, entry, key, original in places:
        cell: Any = entry.get(key)
        if pair(cell) and not frame.inside(*cell):
            raise ScenarioError(off_map(where, original.get(key), cell, frame, source))


def off_map(where: str, metres: Any, cell: list[float], frame: MapFrame, source: str) -> str:
    """The message for a position the map frame puts off the map."""
    (x0, y0), (x1, y1) = frame.to_map(0, frame.rows), frame.to_map(frame.cols, 0)
    return (
        f"{source}: {where} {metres} (metres, map frame) is cell ({cell[0]:.1f}, {cell[1]:.1f}),"
        f" off the map of {frame.cols} x {frame.rows} cells, which covers x {x0:g} to {x1:g} m"
        f" and y {y0:g} to {y1:g} m (origin ({frame.origin[0]:g}, {frame.origin[1]:g}),"
        f" {frame.resolution:g} m per cell). With units: m every position is in metres of the"
        " map frame, y up: check the map's origin, and that the position is not in cells."
    )
