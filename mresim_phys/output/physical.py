"""Results in seconds and metres (output edge): the ``physical`` block of ``summary.json``.

A scenario that gives its step duration ``dt`` (as every scenario with ``units: m`` does,
``scenario/units.py``) gets, beside steps and cells: the run's duration, the milestones in
seconds (``null``: never reached), and with a map resolution (a ROS map's, or
``map.resolution``) distances in metres, the explorable area in square metres and every
robot's final pose in the map frame (x, y in metres, y up, from the map's origin; heading
in degrees counter-clockwise from +x), as RViz would show it. Without ``dt`` nothing is
added: a scenario in cells writes the summary it always wrote.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

from mresim_phys.scenario.frame import MapFrame

if TYPE_CHECKING:
    from mresim_phys.sim import Simulation


def seconds(milestones: dict[str, int | None], dt: float) -> dict[str, float | None]:
    """Milestone steps as seconds (``None`` stays: never reached).

    >>> seconds({"0.5": 66, "0.9": None}, 0.1)
    {'0.5': 6.6, '0.9': None}
    """
    return {k: None if v is None else round(v * dt, 9) for k, v in milestones.items()}


def map_frame(sim: Simulation) -> MapFrame | None:
    """The run's map frame, when its map has a resolution."""
    resolution = sim.setup.resolution
    if resolution is None:
        return None
    rows, cols = sim.setup.truth.occupied.shape
    origin = sim.setup.truth.origin
    return MapFrame(rows, cols, resolution, origin[:2] if origin is not None else (0.0, 0.0))


def pose_m(frame: MapFrame, position: Any, heading: float) -> list[float]:
    """A robot's pose in the map frame: [x, y] metres and the heading in degrees
    counter-clockwise from +x (cells have y down)."""
    x, y = frame.to_map(float(position[0]), float(position[1]))
    return [round(x, 6), round(y, 6), round(-math.degrees(heading), 6) + 0.0]


def physical_summary(sim: Simulation) -> dict[str, Any]:
    """The ``physical`` block for ``summary.json`` ({} without ``dt``)."""
    dt = sim.scenario.dt
    if dt is None:
        return {}
    record, milestones = sim.record, sim.milestones
    block: dict[str, Any] = {
        "dt_s": dt,
        "duration_s": round(record.step * dt, 9),
        "seconds_to_explored": seconds(milestones.explored, dt),
        "seconds_to_known_at_base": seconds(milestones.known_at_base, dt),
    }
    frame = map_frame(sim)
    if frame is not None:
        area = frame.resolution**2
        block |= {
            "resolution_m": frame.resolution,
            "origin_m": list(frame.origin),
            "total_distance_m": record.distance * frame.resolution,
            "explorable_area_m2": int(sim.setup.explorable.mask.sum()) * area,
            "robots": {
                r.name: {
                    "distance_m": r.distance * frame.resolution,
                    "final_pose_m": pose_m(frame, r.position, r.heading),
                }
                for r in sim.robots
            },
        }
    return {"physical": block}
