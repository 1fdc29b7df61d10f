"""Procedural maps (phase 0, input): what ``mresim make-map`` is asked for, validated.

``mresim make-map KIND --seed S --size WxH --out DIR [--set NAME=VALUE ...]``: the kind
(``building``, ``office``, ``cave``, ``rubble``), the seed, the map's size in cells and the
kind's parameters below (each with its default). Every length is in cells. A map too small
for what its parameters ask (a building narrower than two rooms) is refused with a message
naming the parameter (exit 2). How each kind is drawn is in docs/procedural-maps.md.
"""

from __future__ import annotations

from typing import Any, ClassVar, Literal

from pydantic import Field, field_validator, model_validator

from mresim_phys.strict import Strict

Kind = Literal["building", "office", "cave", "rubble", "blueprint"]
MIN_SIZE, MAX_SIZE = 40, 4000  # cells per side


def check_door(door: int, wall: int, side: int, name: str) -> None:
    """A door and a wall either side must fit the shortest wall of a room (``name``)."""
    if door + 2 * wall > side:
        raise ValueError(f"door ({door}) + 2 walls does not fit a {name} wall ({side})")


class KindParams(Strict):
    """Parameters every kind has."""

    KIND: ClassVar[str]
    wall: int = Field(2, ge=1, le=20, description="Wall thickness (cells).")

    def check_size(self, width: int, height: int) -> None:
        """Raise ValueError naming the parameter when a ``width x height`` map cannot hold
        what the parameters ask."""


class BuildingParams(KindParams):
    """Rooms split off a rectangle, a corridor across it, doors between neighbours."""

    KIND: ClassVar[str] = "building"
    room_min: int = Field(16, ge=6, le=400, description="Smallest room side (cells).")
    room_max: int = Field(40, ge=6, le=2000, description="Largest room side before a split.")
    corridor: int = Field(10, ge=0, le=100, description="Corridor width (0: no corridor).")
    door: int = Field(8, ge=2, le=50, description="Door width (cells).")
    loops: float = Field(
        0.25, ge=0, le=1, description="Chance that a wall between rooms not yet joined gets a door."
    )

    @model_validator(mode="after")
    def _ordered(self) -> BuildingParams:
        if self.room_max < 2 * self.room_min:
            raise ValueError(
                f"room_max ({self.room_max}) must be at least 2 * room_min ({2 * self.room_min})"
                " so a room too large can be split into two"
            )
        check_door(self.door, self.wall, self.room_min, "room_min")
        return self

    def check_size(self, width: int, height: int) -> None:
        inner = min(width, height) - 2 * self.wall
        need = 2 * self.room_min + self.wall + self.corridor
        if inner < need:
            raise ValueError(
                f"a {width}x{height} building cannot hold two rooms of room_min {self.room_min}"
                f" beside a corridor of {self.corridor}: give a size of at least"
                f" {need + 2 * self.wall} cells a side, or a smaller room_min"
            )


class OfficeParams(KindParams):
    """A corridor with offices along both sides and cross corridors."""

    KIND: ClassVar[str] = "office"
    office_min: int = Field(16, ge=6, le=400, description="Narrowest office (cells).")
    office_max: int = Field(26, ge=6, le=800, description="Widest office (cells).")
    corridor: int = Field(10, ge=3, le=100, description="Corridor width (cells).")
    door: int = Field(8, ge=2, le=50, description="Door width (cells).")
    cross: int = Field(1, ge=0, le=20, description="Cross corridors joining the two rows.")

    @model_validator(mode="after")
    def _ordered(self) -> OfficeParams:
        if self.office_max < self.office_min:
            raise ValueError(f"office_max ({self.office_max}) is below office_min")
        check_door(self.door, self.wall, self.office_min, "office_min")
        return self

    def check_size(self, width: int, height: int) -> None:
        need_h = self.corridor + 2 * (self.office_min + self.wall) + 2 * self.wall
        need_w = (self.cross + 1) * (self.office_max + self.wall) + self.cross * self.corridor
        if height < need_h or width < need_w + 2 * self.wall:
            raise ValueError(
                f"a {width}x{height} office cannot hold a corridor of {self.corridor} with"
                f" offices of office_min {self.office_min} on both sides and {self.cross} cross"
                f" corridors: give at least {need_w + 2 * self.wall}x{need_h} cells"
            )


class CaveParams(KindParams):
    """A cellular-automaton cave: random rock, smoothed, its largest open space kept."""

    KIND: ClassVar[str] = "cave"
    fill: float = Field(0.45, ge=0.2, le=0.7, description="Share of cells rock at the start.")
    smooth: int = Field(5, ge=0, le=20, description="Smoothing rounds (a cell of 5+ rock is rock).")
    scale: int = Field(3, ge=1, le=20, description="Cells per automaton cell (wider passages).")
    min_open: float = Field(
        0.25, ge=0.05, le=0.9, description="Least share of the map the kept space must cover."
    )


class RubbleParams(KindParams):
    """An open site: rubble pieces, standing wall fragments, an outer wall."""

    KIND: ClassVar[str] = "rubble"
    density: float = Field(0.06, ge=0, le=0.3, description="Share of the site under rubble.")
    piece_max: int = Field(8, ge=1, le=100, description="Largest rubble piece (cells).")
    fragments: int = Field(6, ge=0, le=200, description="Standing wall fragments.")
    fragment_max: int = Field(80, ge=4, le=4000, description="Longest wall fragment (cells).")


class BlueprintParams(KindParams):
    """A simple shape, or shapes joined by '+': loop, corridor, corner, room."""

    KIND: ClassVar[str] = "blueprint"
    shape: str = Field(
        "loop", description="loop, corridor, corner or room, or several joined by '+'."
    )
    corridor: int = Field(12, ge=3, le=200, description="Corridor width (cells).")
    room: float = Field(0.5, ge=0.1, le=0.9, description="A room's share of the map's sides.")

    @field_validator("shape")
    @classmethod
    def _known_shapes(cls, shape: str) -> str:
        parts = shape.split("+")
        unknown = [s for s in parts if s not in ("loop", "corridor", "corner", "room")]
        if unknown or not parts:
            raise ValueError(
                f"shape {shape!r}: each part is one of loop, corridor, corner, room (joined"
                f" by '+'), not {unknown}"
            )
        return shape

    def check_size(self, width: int, height: int) -> None:
        need = 2 * (self.wall + 2 * self.corridor) + 4
        if min(width, height) < need:
            raise ValueError(
                f"a {width}x{height} blueprint cannot hold a loop of corridor {self.corridor}:"
                f" give at least {need} cells a side, or a narrower corridor"
            )


KINDS: dict[str, type[KindParams]] = {
    p.KIND: p for p in (BuildingParams, OfficeParams, CaveParams, RubbleParams, BlueprintParams)
}


class MapRequest(Strict):
    """One ``make-map`` call: kind, seed, size, team to place and the kind's parameters."""

    kind: Kind | Literal["file"]  # file: a map read from disk (mapgen/sets.py)
    seed: int = Field(0, ge=0, le=2**63 - 1)
    width: int = Field(ge=MIN_SIZE, le=MAX_SIZE)
    height: int = Field(ge=MIN_SIZE, le=MAX_SIZE)
    robots: int = Field(4, ge=1, le=256, description="Start positions to place.")
    radius: float = Field(2.0, gt=0, le=50, description="Body radius the places must fit.")
    params: dict[str, Any] = Field(default_factory=dict)

    def kind_params(self) -> KindParams:
        """The kind's parameters, validated (ValueError naming the parameter)."""
        if self.kind == "file":
            raise ValueError("a map file has no kind parameters")
        model = KINDS[self.kind]
        params = model.model_validate(self.params)
        params.check_size(self.width, self.height)
        narrowest = 2 * self.radius + 2  # a body and a cell either side
        for name in ("door", "corridor"):
            width = getattr(params, name, None)
            if width and width < narrowest:
                raise ValueError(
                    f"{name} ({width}) is narrower than a robot of radius {self.radius:g} with"
                    f" a cell to spare on each side ({narrowest:g}): its rooms could not be"
                    f" reached; give a wider {name} or a smaller radius"
                )
        return params
