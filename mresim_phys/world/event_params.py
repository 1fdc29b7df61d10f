"""Event parameters (phase 0, input): every built-in event's ``Params`` model.

Pydantic and the standard library only: :mod:`mresim_phys.world.event_catalog` enters each
built-in event with its model here and its class (``world/events.py``) by reference, so
the scenario schema validates every ``events`` entry without importing what the event does.

What an event touches is declared by its ``Params``, never found by checking its class:
:attr:`EventParams.changes` (``world``, ``robots``, ``radio``: a run whose events change
the world keeps 'latest' beliefs), :meth:`EventParams.agent_names` (checked against the
team), :meth:`EventParams.boxes` (checked against the map), :meth:`EventParams.doors`
(checked against the doors list) and :meth:`EventParams.under` (its files, made absolute
when the scenario is read).
"""

from __future__ import annotations

from pathlib import Path
from typing import ClassVar, Literal

from pydantic import Field, model_validator

from mresim_phys.plugin import PluginParams
from mresim_phys.world.element_params import Crush
from mresim_phys.world.parts import (
    FaultPart,
    LocalizationMode,
    check_localization,
    check_part,
    distance_field,
    factor_field,
    mode_field,
    part_field,
)
from mresim_phys.world.shapes import BoxRegion, Region, region_under

RobotPart = FaultPart


Channels = Literal["main", "control", "both"]


Box = tuple[int, int, int, int]  # row0, row1, col0, col1 (half-open)


Changes = Literal["world", "robots", "radio"]


class EventParams(PluginParams):
    """Base for every event's parameters: the step at which it happens, and what the event
    touches (module docstring)."""

    step: int = Field(ge=0, description="Step at which the event happens.")
    changes: ClassVar[frozenset[Changes]] = frozenset()  # what the event may change

    def doors(self) -> list[tuple[str, str]]:
        """(field, door name) for every door the event names (checked against ``doors``)."""
        return []

    def under(self, folder: Path) -> EventParams:
        """The params with every file they name made absolute (relative to ``folder``, the
        scenario file's folder)."""
        return self

    def agent_names(self) -> list[tuple[str, str, bool]]:
        """(field, agent name, whether 'base' may be named) for every agent the event names.

        Loading checks each against the team, so a misspelt name is an error before
        anything runs.
        """
        return []

    def boxes(self) -> list[tuple[str, Box]]:
        """(field, (row0, row1, col0, col1)) for every map window the event names.

        Building the run checks each against the map.
        """
        return []


class FailParams(EventParams):
    """At ``step``, robot ``fail`` stops (or loses one ``part``), for good or until ``until``."""

    fail: str = Field(description="Name of the robot that fails.")
    part: RobotPart = part_field()
    speed_factor: float | None = factor_field("the robot's speed")
    range_factor: float | None = factor_field("the sensor range")
    until: int | None = Field(
        None, ge=1, description="Step at which the part works again (null: never)."
    )
    mode: LocalizationMode | None = mode_field()
    distance: float | None = distance_field()
    changes: ClassVar[frozenset[Changes]] = frozenset({"robots"})

    def agent_names(self) -> list[tuple[str, str, bool]]:
        """The failing robot."""
        return [("fail", self.fail, False)]

    @model_validator(mode="after")
    def _checked(self) -> FailParams:
        check_part(self.part, self.speed_factor, self.range_factor)
        check_localization(self.part, self.mode, self.distance)
        if self.mode == "jump" and self.until is not None:
            raise ValueError("a jump is over at once: give no 'until'")
        if self.until is not None and self.until <= self.step:
            raise ValueError(f"'until' ({self.until}) must come after 'step' ({self.step})")
        return self


class BlackoutParams(EventParams):
    """From ``step`` until before ``until``, the named agents can neither send nor receive."""

    step: int = Field(ge=0, description="First step of the blackout.")
    until: int = Field(ge=1, description="First step after the blackout.")
    blackout: list[str] = Field(min_length=1, description="Robot names (or 'base') that go silent.")
    channel: Channels = Field("both", description="Which channel goes silent.")
    changes: ClassVar[frozenset[Changes]] = frozenset({"radio"})

    def agent_names(self) -> list[tuple[str, str, bool]]:
        """The silenced agents (the base may be one)."""
        return [(f"blackout[{k}]", name, True) for k, name in enumerate(self.blackout)]

    @model_validator(mode="after")
    def _ordered(self) -> BlackoutParams:
        if self.until <= self.step:
            raise ValueError(f"'until' ({self.until}) must be after 'step' ({self.step})")
        return self


class CellsParams(EventParams):
    """At ``step``, the cells of a window become walls (a collapse) or free (rubble cleared)."""

    cells: tuple[int, int, int, int] = Field(
        description="The window [x0, y0, x1, y1] in cells: columns x0..x1-1, rows y0..y1-1."
    )
    occupied: bool = Field(True, description="True: the cells become walls; false: free.")
    changes: ClassVar[frozenset[Changes]] = frozenset({"world"})

    @model_validator(mode="after")
    def _non_empty(self) -> CellsParams:
        x0, y0, x1, y1 = self.cells
        if not (0 <= x0 < x1 and 0 <= y0 < y1):
            raise ValueError(f"'cells' {list(self.cells)} must have 0 <= x0 < x1 and 0 <= y0 < y1")
        return self

    def boxes(self) -> list[tuple[str, Box]]:
        """The window, as (row0, row1, col0, col1)."""
        x0, y0, x1, y1 = self.cells
        return [("cells", (y0, y1, x0, x1))]


class CollapseParams(EventParams):
    """At ``step``, a region turns to rubble (or a wall gives way: ``becomes: free``)."""

    collapse: Region = Field(
        description="{box: [x0, y0, x1, y1]}, {circle: [x, y, r]}, {polygon: [[x, y], ...]}"
        " or {mask: file.png} (dark pixels; the map's size; relative to the scenario file)."
    )
    becomes: Literal["obstacle", "free"] = Field("obstacle", description="What the region becomes.")
    crush: Crush = Field(
        "avoid", description="avoid: rubble lands around robots; fail: robots under it fail."
    )
    changes: ClassVar[frozenset[Changes]] = frozenset({"world", "robots"})

    def under(self, folder: Path) -> CollapseParams:
        """A mask region's image path made absolute."""
        return self.model_copy(update={"collapse": region_under(self.collapse, folder)})

    def boxes(self) -> list[tuple[str, Box]]:
        """A box region, as (row0, row1, col0, col1)."""
        if isinstance(self.collapse, BoxRegion):
            x0, y0, x1, y1 = self.collapse.box
            return [("collapse", (y0, y1, x0, x1))]
        return []


class DoorEventParams(EventParams):
    """Base of the events that close or open a door."""

    changes: ClassVar[frozenset[Changes]] = frozenset({"world"})


class CloseParams(DoorEventParams):
    """At ``step``, door ``close`` closes (as soon as nothing is in its way)."""

    close: str = Field(description="Name of a door of the scenario's doors list.")

    def doors(self) -> list[tuple[str, str]]:
        """The door that closes."""
        return [("close", self.close)]


class OpenParams(DoorEventParams):
    """At ``step``, door ``open`` opens."""

    open: str = Field(description="Name of a door of the scenario's doors list.")

    def doors(self) -> list[tuple[str, str]]:
        """The door that opens."""
        return [("open", self.open)]
