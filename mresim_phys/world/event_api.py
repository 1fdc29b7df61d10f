"""The events' interface (phase 0 of every step): what an event is and what it may do.

:class:`Event` (a registry name, a ``Params`` model, :meth:`Event.apply`), the
:class:`EventContext` through which an event acts on a running simulation (see the robots,
fail a robot or part of one, silence agents, change the world, log a line, draw from the
event's own named random stream), the read-only :class:`RobotInfo` it sees of each robot,
and :class:`NeedsMap` for an event that works out where it acts before the run starts.
The built-in events are in ``events.py``; the registry, which names this protocol, in
``event_catalog.py``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar, Protocol, runtime_checkable

from mresim_phys.world.element_params import Crush
from mresim_phys.world.event_params import Box, Channels, EventParams, RobotPart

if TYPE_CHECKING:
    import numpy as np

    from mresim_phys.types import BoolGrid


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

    def jump(self, robot: str, distance: float) -> None:
        """Robot ``robot``'s believed pose is thrown ``distance`` cells off at once (a
        localisation fault: the kidnapped robot; it must have localisation)."""
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


@runtime_checkable
class NeedsMap(Protocol):
    """An event that works out where it acts on the map before the run starts."""

    def prepare(self, shape: tuple[int, int]) -> None:
        """Fix the cells it acts on for a map of ``shape`` (ValueError: it cannot)."""
        ...
