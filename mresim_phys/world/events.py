"""Events (phase 0 of every step): scheduled changes to the team, the radio and the world.

Events are a plugin family like strategies, comm models and planners: a
:class:`Event` Protocol, the :data:`EVENTS` registry keyed by the YAML key that
marks an entry (``{step: 300, fail: B}`` is a ``fail`` event), and a ``Params``
model per event that the scenario schema validates each entry against (the
schema's event union and the scenario reference are generated from the
registry). Each step the simulation calls every event's :meth:`Event.apply`
with an :class:`EventContext`: the small surface through which an event acts
(see the robots, fail a robot or part of one, silence agents, change the world, log a
line, draw from the event's own named random stream).

What an event touches is declared by its ``Params``, never found by checking its class:
:attr:`EventParams.changes` (``world``, ``robots``, ``radio``: a run whose events change
the world keeps 'latest' beliefs), :meth:`EventParams.agent_names` (checked against the
team), :meth:`EventParams.boxes` (checked against the map), :meth:`EventParams.doors`
(checked against the doors list) and :meth:`EventParams.under` (its files, made absolute
when the scenario is read). An event that needs the map before the run starts has
:meth:`NeedsMap.prepare`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar, Literal, Protocol, runtime_checkable

import numpy as np
from pydantic import Field, model_validator

from mresim_phys.plugin import Family, Plugin, PluginParams
from mresim_phys.registry import Registry
from mresim_phys.types import BoolGrid
from mresim_phys.world.debris import Crush
from mresim_phys.world.parts import FaultPart, check_part, factor_field, factors_of, part_field
from mresim_phys.world.shapes import BoxRegion, Region, region_cells, region_under

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


@dataclass(frozen=True)
class RobotInfo:
    """What an event may see of a robot: where it is and whether it works."""

    name: str
    position: tuple[float, float]  # (x, y) cells
    heading: float  # radians
    radius: float
    state: str  # active, done, error or failed
    broken: tuple[str, ...]  # the parts that do not work now (faults.md)


class EventContext(Protocol):
    """What an event may do to the running simulation (and nothing more)."""

    @property
    def step(self) -> int:
        """The step now starting."""
        ...

    @property
    def robots(self) -> Sequence[RobotInfo]:
        """Every robot as it stands at the start of the step (scenario order; read only)."""
        ...

    @property
    def rng(self) -> np.random.Generator:
        """The applying event's own named random stream (same seed, same draws)."""
        ...

    def fail(
        self, robot: str, part: RobotPart = "robot", factors: tuple[float, float] = (1.0, 1.0)
    ) -> None:
        """Robot ``robot`` loses ``part`` (``robot``: everything; ``degraded``: its speed
        and sensor range are scaled by ``factors``) until a matching :meth:`repair`."""
        ...

    def repair(
        self, robot: str, part: RobotPart = "robot", factors: tuple[float, float] = (1.0, 1.0)
    ) -> None:
        """Undo one failure of ``part`` of robot ``robot`` (a reboot)."""
        ...

    def silence(self, agents: Sequence[str], until: int, channels: Channels) -> None:
        """``agents`` (robot names or 'base') neither send nor receive until before ``until``."""
        ...

    def change_world(self, box: Box, occupied: BoolGrid | bool) -> None:
        """Set the true occupancy of ``box`` (walls appear or clear; rays and radio follow)."""
        ...

    def change_cells(self, cells: BoolGrid, occupied: bool, crush: Crush) -> list[str]:
        """Make the True cells of the map-sized mask ``cells`` walls or free; rubble never
        lands on a robot (``crush: avoid``: its cells stay free) unless ``crush: fail``
        (the robot is buried and fails). Returns the robots spared or buried."""
        ...

    def set_door(self, name: str, closed: bool) -> None:
        """Ask door ``name`` to close or open (it closes once nothing is in its way)."""
        ...

    def log(self, line: str) -> None:
        """Note what happened this step (run log, videos' event line)."""
        ...


@runtime_checkable
class Event(Protocol):
    """A scheduled event: built from its validated params, asked to act every step."""

    name: ClassVar[str]
    Params: ClassVar[type[EventParams]]

    @property
    def params(self) -> EventParams:
        """The validated parameters it was built from (read only: a subclass may narrow it)."""
        ...

    def apply(self, context: EventContext) -> None:
        """Act if this event has anything to do at ``context.step``."""
        ...


EVENTS: Registry[Event] = Registry("event", "mresim_phys.events", Family(Event, EventParams))


@runtime_checkable
class NeedsMap(Protocol):
    """An event that works out where it acts on the map before the run starts."""

    def prepare(self, shape: tuple[int, int]) -> None:
        """Fix the cells it acts on for a map of ``shape`` (ValueError: it cannot)."""
        ...


class FailParams(EventParams):
    """At ``step``, robot ``fail`` stops (or loses one ``part``), for good or until ``until``."""

    fail: str = Field(description="Name of the robot that fails.")
    part: RobotPart = part_field()
    speed_factor: float | None = factor_field("the robot's speed")
    range_factor: float | None = factor_field("the sensor range")
    until: int | None = Field(
        None, ge=1, description="Step at which the part works again (null: never)."
    )
    changes: ClassVar[frozenset[Changes]] = frozenset({"robots"})

    def agent_names(self) -> list[tuple[str, str, bool]]:
        """The failing robot."""
        return [("fail", self.fail, False)]

    @model_validator(mode="after")
    def _checked(self) -> FailParams:
        check_part(self.part, self.speed_factor, self.range_factor)
        if self.until is not None and self.until <= self.step:
            raise ValueError(f"'until' ({self.until}) must come after 'step' ({self.step})")
        return self


@EVENTS.register
class Failure(Plugin):
    """A robot, or one of its parts, fails (for good, or until a later step)."""

    name = "fail"
    Params: ClassVar[type[EventParams]] = FailParams
    params: FailParams

    def __init__(self, params: FailParams) -> None:
        self.params = params

    def apply(self, context: EventContext) -> None:
        """Fail the robot (or part) at its step; repair it at ``until``."""
        p = self.params
        factors = factors_of(p.speed_factor, p.range_factor)
        suffix = "" if p.part == "robot" else f" {p.part}"
        if context.step == p.step:
            context.fail(p.fail, p.part, factors)
            context.log(f"fail {p.fail}{suffix}")
        elif context.step == p.until:
            context.repair(p.fail, p.part, factors)
            context.log(f"recover {p.fail}{suffix}")


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


@EVENTS.register
class Blackout(Plugin):
    """Agents go silent on a channel for a while (jamming, a dead zone, a radio reset)."""

    name = "blackout"
    Params: ClassVar[type[EventParams]] = BlackoutParams
    params: BlackoutParams

    def __init__(self, params: BlackoutParams) -> None:
        self.params = params

    def apply(self, context: EventContext) -> None:
        """Silence the agents at ``step``; note the end at ``until``."""
        p = self.params
        who = f"{','.join(p.blackout)} ({p.channel})"
        if context.step == p.step:
            context.silence(p.blackout, p.until, p.channel)
            context.log(f"blackout {who} until {p.until}")
        elif context.step == p.until:
            context.log(f"blackout over {who}")


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


@EVENTS.register
class Cells(Plugin):
    """Part of the building changes: a window of cells becomes wall or free space."""

    name = "cells"
    Params: ClassVar[type[EventParams]] = CellsParams
    params: CellsParams

    def __init__(self, params: CellsParams) -> None:
        self.params = params

    def apply(self, context: EventContext) -> None:
        """Change the cells at the event's step."""
        p = self.params
        if context.step == p.step:
            context.change_world(p.boxes()[0][1], p.occupied)
            what = "walls" if p.occupied else "free"
            context.log(f"cells {list(p.cells)} {what}")


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


@EVENTS.register
class Collapse(Plugin):
    """Part of the building collapses (or opens up) at a step."""

    name = "collapse"
    Params: ClassVar[type[EventParams]] = CollapseParams
    params: CollapseParams

    def __init__(self, params: CollapseParams) -> None:
        self.params = params
        self.cells: BoolGrid | None = None  # the region on the map, set when the run is built

    def prepare(self, shape: tuple[int, int]) -> None:
        """The region's cells on a map of ``shape`` (ValueError: it does not fit)."""
        self.cells = region_cells(self.params.collapse, shape)

    def apply(self, context: EventContext) -> None:
        """Change the region at the event's step."""
        p = self.params
        if context.step != p.step or self.cells is None:
            return
        occupied = p.becomes == "obstacle"
        robots = context.change_cells(self.cells, occupied, p.crush)
        region = p.collapse.model_dump(mode="json")
        line = f"collapse {region} {'rubble' if occupied else 'free'}"
        if robots and occupied:
            line += f" ({'buries' if p.crush == 'fail' else 'spares'} {', '.join(robots)})"
        context.log(line)


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


@EVENTS.register
class Close(Plugin):
    """A door closes."""

    name = "close"
    Params: ClassVar[type[EventParams]] = CloseParams
    params: CloseParams

    def __init__(self, params: CloseParams) -> None:
        self.params = params

    def apply(self, context: EventContext) -> None:
        """Ask the door to close at the event's step."""
        if context.step == self.params.step:
            context.set_door(self.params.close, True)


@EVENTS.register
class Open(Plugin):
    """A door opens."""

    name = "open"
    Params: ClassVar[type[EventParams]] = OpenParams
    params: OpenParams

    def __init__(self, params: OpenParams) -> None:
        self.params = params

    def apply(self, context: EventContext) -> None:
        """Ask the door to open at the event's step."""
        if context.step == self.params.step:
            context.set_door(self.params.open, False)


def make_event(params: EventParams) -> Event:
    """The event a validated entry describes (its registry entry is the one whose Params it is)."""
    for name in EVENTS.names():
        cls = EVENTS.get(name)
        if type(params) is cls.Params:
            return EVENTS.make(name, params.model_dump())
    raise ValueError(f"no registered event takes {type(params).__name__}")
