"""World elements' parameters (phase 0, input): moving obstacles, doors, debris, terrain.

The validated models of a scenario's ``obstacles``, ``doors``, ``random_debris`` and
``terrain`` keys, in pydantic and the standard library only, so a scenario is validated
without numpy, pymunk or OpenCV. What each element does in a run lives beside it:
``obstacles.py``, ``doors.py``, ``debris.py``, ``terrain.py``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Annotated, Any, ClassVar, Literal, Protocol, TypeVar

from pydantic import Field, Tag, model_validator

from mresim_phys.strict import Strict
from mresim_phys.world.shapes import (
    BodyShape,
    BoxRegion,
    CircleRegion,
    MaskRegion,
    PolygonRegion,
    Region,
    keyed,
)

Point = tuple[float, float]


Crush = Literal["avoid", "fail"]


class RandomDebrisParams(Strict):
    """Rubble falling at random (``random_debris``)."""

    rate: float = Field(ge=0, le=1, description="Probability that a piece falls at a step.")
    size: tuple[int, int] = Field((2, 6), description="[min, max] side of a piece, cells.")
    region: Region | None = Field(None, description="Where pieces fall (null: anywhere).")
    after: int = Field(0, ge=0, description="First step at which pieces may fall.")
    until: int | None = Field(None, ge=1, description="Last step (null: to the end of the run).")
    crush: Crush = Field("avoid", description="avoid: rubble lands around robots; fail: buries.")

    @model_validator(mode="after")
    def _ranges(self) -> RandomDebrisParams:
        low, high = self.size
        if not 1 <= low <= high <= 1000:
            raise ValueError(f"'size' {list(self.size)} must be [min, max] with 1 <= min <= max")
        if self.until is not None and self.until < self.after:
            raise ValueError(f"'until' ({self.until}) must not come before 'after' ({self.after})")
        return self


class DoorParams(Strict):
    """One door of a scenario (``doors[i]``)."""

    name: str = Field(min_length=1, description="Its name, used by close / open events.")
    between: tuple[Point, Point] = Field(description="Its two ends [[x0, y0], [x1, y1]], cells.")
    thickness: float = Field(1.0, gt=0, le=100, description="Width of the door leaf, cells.")
    closed: bool = Field(False, description="Closed at step 0.")
    period: int | None = Field(
        None, ge=2, description="Cycle length in steps (null: it changes only on events)."
    )
    open_for: int | None = Field(None, ge=1, description="Open steps at the start of each cycle.")
    offset: int = Field(0, ge=0, description="Step at which the first cycle starts.")

    @model_validator(mode="after")
    def _cycle(self) -> DoorParams:
        (x0, y0), (x1, y1) = self.between
        if math.hypot(x1 - x0, y1 - y0) < 1.0:
            raise ValueError(
                f"'between': the door's ends {list(self.between[0])} and {list(self.between[1])}"
                " are less than a cell apart; give the two ends of the doorway"
            )
        if (self.period is None) != (self.open_for is None):
            raise ValueError("a periodic door needs both 'period' and 'open_for'")
        if self.period is not None and self.open_for is not None and self.open_for >= self.period:
            raise ValueError(
                f"'open_for' ({self.open_for}) must be less than 'period' ({self.period})"
            )
        return self

    def points(self) -> list[Point]:
        """Both ends (checked against the map when the run is built)."""
        return list(self.between)

    def wanted_closed(self, step: int, scheduled: bool) -> bool:
        """Whether the door should be closed at ``step``; ``scheduled`` is the state the
        close / open events have asked for (used when the door does not cycle)."""
        if self.period is None or self.open_for is None or step < self.offset:
            return scheduled
        return (step - self.offset) % self.period >= self.open_for


class WaypointsMotion(Strict):
    """Along a list of points at a constant speed."""

    waypoints: list[Point] = Field(min_length=1, description="Points [[x, y], ...] in cells.")
    speed: float = Field(1.0, gt=0, le=1000, description="Cells per step.")
    mode: Literal["loop", "back_and_forth", "once"] = Field(
        "loop", description="After the last point: back to the first, reverse, or stop."
    )


class RandomWalkMotion(Strict):
    """A random walk from a start point."""

    random_walk: Point = Field(description="The start [x, y] in cells.")
    speed: float = Field(1.0, gt=0, le=1000, description="Cells per step.")
    turn_rate: float = Field(
        30.0, ge=0, le=180, description="Largest change of heading per step, degrees."
    )


class StillMotion(Strict):
    """Standing at one point."""

    still: Point = Field(description="Where it stands [x, y] in cells.")


Motion = Annotated[
    Annotated[WaypointsMotion, Tag("waypoints")]
    | Annotated[RandomWalkMotion, Tag("random_walk")]
    | Annotated[StillMotion, Tag("still")],
    keyed("waypoints", "random_walk", "still"),
]


class ObstacleParams(Strict):
    """One moving obstacle of a scenario (``obstacles[i]``)."""

    name: str = Field(min_length=1, description="Its name, unique among obstacles and doors.")
    shape: BodyShape = Field(description="{circle: r}, {box: [w, h]} or {polygon: [[x, y], ...]}.")
    motion: Motion = Field(
        description="{waypoints: [[x, y], ...]}, {random_walk: [x, y]} or {still: [x, y]}."
    )
    appear: int = Field(0, ge=0, description="Step at which it enters the map.")
    remove: int | None = Field(None, ge=1, description="Step at which it leaves (null: never).")
    blocks_radio: bool = Field(
        True, description="Whether line of sight and path loss count it as a wall."
    )

    @model_validator(mode="after")
    def _life(self) -> ObstacleParams:
        if self.remove is not None and self.remove <= self.appear:
            raise ValueError(f"'remove' ({self.remove}) must come after 'appear' ({self.appear})")
        return self

    def points(self) -> list[Point]:
        """Every point of its motion (checked against the map when the run is built)."""
        motion = self.motion
        if isinstance(motion, WaypointsMotion):
            return list(motion.waypoints)
        if isinstance(motion, RandomWalkMotion):
            return [motion.random_walk]
        return [motion.still]


SHAPE_KEYS = ("box", "circle", "polygon", "mask")


class ShapedRegion(Strict):
    """A region of the map given by one of ``box``, ``circle``, ``polygon``, ``mask``."""

    KIND: ClassVar[str] = "a region"  # what errors call it
    box: tuple[int, int, int, int] | None = Field(None, description="[x0, y0, x1, y1] in cells.")
    circle: tuple[float, float, float] | None = Field(None, description="[x, y, r] in cells.")
    polygon: list[tuple[float, float]] | None = Field(
        None, min_length=3, description="Vertices [[x, y], ...] in cells."
    )
    mask: Path | None = Field(None, description="PNG the size of the map; dark pixels are in.")

    @model_validator(mode="after")
    def _one_shape(self) -> ShapedRegion:
        given = [k for k in SHAPE_KEYS if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError(
                f"{self.KIND} needs exactly one of 'box', 'circle', 'polygon' or 'mask'"
                f" (got {given or 'none'})"
            )
        self.region()  # the shape's own checks (a box's corners in order, r > 0)
        return self

    def region(self) -> Region:
        """The shape as a region model of :mod:`mresim_phys.world.shapes`."""
        if self.box is not None:
            return BoxRegion(box=self.box)
        if self.circle is not None:
            return CircleRegion(circle=self.circle)
        if self.polygon is not None:
            return PolygonRegion(polygon=self.polygon)
        assert self.mask is not None
        return MaskRegion(mask=self.mask)


class TerrainRegion(ShapedRegion):
    """One region of slower ground: one of ``box``, ``circle``, ``polygon``, ``mask``."""

    KIND: ClassVar[str] = "a terrain region"
    factor: float = Field(gt=0, le=1, description="Speed factor on the region, in (0, 1].")


class TerrainSpec(Strict):
    """Variable terrain: a greyscale ``image`` or a list of ``regions`` (exactly one)."""

    image: Path | None = Field(
        None,
        description="Greyscale image the size of the map: factor = max(min_factor, value/255).",
    )
    min_factor: float = Field(
        0.1, gt=0, le=1, description="Image terrain: the slowest factor (black pixels)."
    )
    regions: list[TerrainRegion] | None = Field(
        None, description="Regions with a speed factor each; other cells are 1 (later wins)."
    )

    @model_validator(mode="after")
    def _one_source(self) -> TerrainSpec:
        if (self.image is None) == (self.regions is None):
            raise ValueError("give exactly one of 'image: file.png' or 'regions: [...]'")
        return self


class ImageLayer(Protocol):
    """A map layer given by an image and regions (terrain, ground classes)."""

    @property
    def image(self) -> Path | None: ...
    @property
    def regions(self) -> Sequence[ShapedRegion] | None: ...
    def model_copy(self, *, update: Mapping[str, Any] | None = None, deep: bool = False) -> Any: ...


L = TypeVar("L", bound=ImageLayer)


def absolute_layer(spec: L | None, folder: Path) -> L | None:
    """``spec`` with its image and mask paths made absolute (relative to ``folder``)."""
    if spec is None:
        return None
    image = spec.image and (folder / spec.image.expanduser()).resolve()
    regions = spec.regions and [
        r.model_copy(update={"mask": r.mask and (folder / r.mask.expanduser()).resolve()})
        for r in spec.regions
    ]
    copied: L = spec.model_copy(update={"image": image, "regions": regions})
    return copied
