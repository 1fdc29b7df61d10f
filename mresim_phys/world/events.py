"""Events (phase 0 of every step): the built-in scheduled changes to the team, the radio and
the world: ``fail``, ``blackout``, ``cells``, ``collapse``, ``close`` and ``open``.

Events are a plugin family like strategies, comm models and planners: the
:class:`~mresim_phys.world.event_api.Event` Protocol and the :class:`EventContext` an event
acts through (``world/event_api.py``), the ``EVENTS`` registry keyed by the YAML key that
marks an entry (``world/event_catalog.py``: ``{step: 300, fail: B}`` is a ``fail`` event),
and a ``Params`` model per event (``world/event_params.py``) that the scenario schema
validates each entry against. Each step the simulation calls every event's ``apply`` with
the run's context. What an event touches is declared by its ``Params``, never found by
checking its class; an event that needs the map before the run starts has
:meth:`~mresim_phys.world.event_api.NeedsMap.prepare`.
"""

from __future__ import annotations

from typing import ClassVar

from mresim_phys.plugin import Plugin
from mresim_phys.types import BoolGrid
from mresim_phys.world.event_api import Event, EventContext
from mresim_phys.world.event_catalog import EVENTS
from mresim_phys.world.event_params import (
    BlackoutParams,
    CellsParams,
    CloseParams,
    CollapseParams,
    EventParams,
    FailParams,
    OpenParams,
)
from mresim_phys.world.footprints import region_cells
from mresim_phys.world.parts import factors_of


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
        if context.step == p.step and p.mode == "jump" and p.distance is not None:
            context.jump(p.fail, p.distance)
            context.log(f"jump {p.fail} localization {p.distance:g} cells")
        elif context.step == p.step:
            context.fail(p.fail, p.part, factors)
            context.log(f"fail {p.fail}{suffix}")
        elif context.step == p.until:
            context.repair(p.fail, p.part, factors)
            context.log(f"recover {p.fail}{suffix}")


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
