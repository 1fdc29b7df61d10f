"""Scenario units (phase 0, input): the map frame and the conversions of one figure.

:class:`MapFrame` says where a map's cells lie in the map frame (metres, y up, from the
map's origin, as ROS and RViz place them); :class:`Converter` turns one figure given in
metres, metres per second or map-frame points into cells, cells per step or cell
coordinates. ``scenario/units.py`` applies them to a whole scenario (``units: m``);
``output/physical.py`` uses the frame to report poses in metres.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from mresim_phys.errors import ScenarioError


@dataclass(frozen=True)
class MapFrame:
    """Where the map's cells lie in the map frame: ``rows`` x ``cols`` cells of
    ``resolution`` metres, the lower-left corner at ``origin`` (x, y, metres)."""

    rows: int
    cols: int
    resolution: float
    origin: tuple[float, float] = (0.0, 0.0)

    def to_cell(self, x: float, y: float) -> tuple[float, float]:
        """A map-frame point (metres, y up) as cell coordinates (x = column, y = row down).

        >>> MapFrame(100, 200, 0.05, (-7.5, -5.0)).to_cell(-7.5, -5.0)
        (0.0, 100.0)
        """
        ox, oy = self.origin
        return tidy((x - ox) / self.resolution), tidy(self.rows - (y - oy) / self.resolution)

    def to_map(self, x: float, y: float) -> tuple[float, float]:
        """Cell coordinates as a map-frame point (metres, y up): :meth:`to_cell` undone.

        >>> MapFrame(100, 200, 0.05, (-7.5, -5.0)).to_map(0.0, 100.0)
        (-7.5, -5.0)
        """
        ox, oy = self.origin
        return ox + x * self.resolution, oy + (self.rows - y) * self.resolution

    def inside(self, x: float, y: float) -> bool:
        """Whether cell coordinates lie on the map."""
        return 0 <= x <= self.cols and 0 <= y <= self.rows


def tidy(value: float) -> float:
    """A converted figure rounded to 1e-9 (of a cell): 12.25 m at 0.05 m per cell is 245
    cells, not 245.00000000000003, so a scenario in metres runs exactly as the same one in
    cells.

    >>> tidy(12.25 / 0.05)
    245.0
    """
    return round(value, 9) + 0.0


def number(value: Any) -> bool:
    """A YAML number (not a bool): what a conversion may touch; anything else is left for
    the schema to reject."""
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def pair(value: Any) -> bool:
    """A list of two numbers."""
    return isinstance(value, list | tuple) and len(value) == 2 and all(number(v) for v in value)


@dataclass(frozen=True)
class Converter:
    """The conversions of one scenario: its map frame and step duration."""

    frame: MapFrame
    dt: float | None
    source: str

    def length(self, value: Any) -> Any:
        """Metres -> cells."""
        return tidy(value / self.frame.resolution) if number(value) else value

    def cells(self, value: Any) -> Any:
        """Metres -> a whole number of cells, at least 1 (debris sizes)."""
        return max(1, round(value / self.frame.resolution)) if number(value) else value

    def per_length(self, value: Any) -> Any:
        """Per metre -> per cell (a battery's charge per metre moved)."""
        return tidy(value * self.frame.resolution) if number(value) else value

    def speed(self, value: Any, where: str) -> Any:
        """Metres per second -> cells per step (needs ``dt``)."""
        if not number(value):
            return value
        if self.dt is None:
            raise ScenarioError(
                f"{self.source}: {where} is a speed, and with 'units: m' speeds are metres per"
                " second; give the step duration 'dt' (seconds per step, e.g. dt: 0.1) at the"
                " top of the scenario so it can be turned into cells per step."
            )
        return tidy(value * self.dt / self.frame.resolution)

    def point(self, value: Any) -> Any:
        """A map-frame point -> cell coordinates."""
        return list(self.frame.to_cell(*value)) if pair(value) else value

    def offset(self, value: Any) -> Any:
        """A vector relative to a centre (metres, y up) -> cells (y down)."""
        if not pair(value):
            return value
        return [self.length(value[0]), -self.length(value[1])]

    def heading(self, value: Any) -> Any:
        """Counter-clockwise degrees with y up -> degrees with y down."""
        return -value if number(value) else value

    def box(self, value: Any) -> Any:
        """[x0, y0, x1, y1] in the map frame -> the same box in cells (corners sorted)."""
        if not (isinstance(value, list | tuple) and len(value) == 4 and all(map(number, value))):
            return value
        (a, b), (c, d) = self.frame.to_cell(*value[:2]), self.frame.to_cell(*value[2:])
        return [min(a, c), min(b, d), max(a, c), max(b, d)]

    def window(self, value: Any) -> Any:
        """A box in the map frame -> the window of whole cells it covers."""
        found = self.box(value)
        if found is value:
            return value
        return [math.floor(found[0]), math.floor(found[1]), math.ceil(found[2]),
                math.ceil(found[3])]  # fmt: skip

    def region(self, value: Any) -> Any:
        """{box}, {circle: [x, y, r]} or {polygon} in the map frame -> cells (a mask stays)."""
        if not isinstance(value, dict):
            return value
        out = dict(value)
        if "box" in out:
            out["box"] = self.box(out["box"])
        circle = out.get("circle")
        if isinstance(circle, list) and len(circle) == 3 and all(map(number, circle)):
            out["circle"] = [*self.frame.to_cell(*circle[:2]), self.length(circle[2])]
        if isinstance(out.get("polygon"), list):
            out["polygon"] = [self.point(p) for p in out["polygon"]]
        return out

    def shape(self, value: Any) -> Any:
        """An obstacle's shape around its centre: {circle: r}, {box: [w, h]}, {polygon}."""
        if not isinstance(value, dict):
            return value
        out = dict(value)
        if "circle" in out:
            out["circle"] = self.length(out["circle"])
        if pair(out.get("box")):
            out["box"] = [self.length(v) for v in out["box"]]
        if isinstance(out.get("polygon"), list):
            out["polygon"] = [self.offset(p) for p in out["polygon"]]
        return out


def mapping(value: Any) -> dict[str, Any] | None:
    """``value`` if it is a mapping with text keys, else None."""
    return value if isinstance(value, dict) else None
