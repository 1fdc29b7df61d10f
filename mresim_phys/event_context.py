"""Events phase (phase 0 of a step): the context through which events act on a run.

:class:`RunEventContext` implements :class:`~mresim_phys.world.events.EventContext`
over the running simulation's parts: robots fail (whole or one part), agents
fall silent through the network's blackouts, the true world changes (the
connected free space and the explorable area the coverage counts follow), lines are
logged for the step, and
each event draws only from its own named random stream.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from mresim_phys.agents import Agent, Robot
from mresim_phys.comms.network import Blackout, Network
from mresim_phys.knowledge.coverage import Coverage
from mresim_phys.localization.faults import jump_belief
from mresim_phys.types import BoolGrid, FloatArray
from mresim_phys.world.changes import Change, circles_cover
from mresim_phys.world.doors import Door
from mresim_phys.world.element_params import Crush
from mresim_phys.world.elements import WorldElement
from mresim_phys.world.event_api import Event, RobotInfo
from mresim_phys.world.event_params import Box, Channels, RobotPart
from mresim_phys.world.explorable import Explorable, follow_world
from mresim_phys.world.reach import Reachable
from mresim_phys.world.space import World

CHANNELS: dict[str, tuple[str, ...]] = {
    "main": ("main",),
    "control": ("control",),
    "both": ("main", "control"),
}


class RunEventContext:
    """What events may do to one run; :meth:`run` applies every event at a step."""

    def __init__(
        self,
        agents: Sequence[Agent],
        network: Network,
        world: World,
        coverage: Coverage,
        reaches: tuple[Reachable, Explorable],
        streams: Sequence[np.random.Generator],
        elements: Sequence[WorldElement] = (),
    ) -> None:
        self.agents = {a.name: a for a in agents}
        self.network, self.world, self.coverage = network, world, coverage
        self.reachable, self.explorable = reaches
        self.streams = list(streams)
        self.elements = list(elements)
        self.doors = {e.params.name: e for e in self.elements if isinstance(e, Door)}
        self.lines: list[str] = []
        self._step = 0
        self._current = 0
        self._bodies: FloatArray | None = None  # (x, y, radius) of every robot this step
        self._robots: tuple[RobotInfo, ...] | None = None  # what events see of them

    def run(self, events: Sequence[Event], step: int) -> list[str]:
        """Apply every event (in scenario order), then move every world element (moving
        obstacles, doors, debris; in scenario order) at ``step``; return the lines logged."""
        self._step, self.lines, self._bodies, self._robots = step, [], None, None
        for index, event in enumerate(events):
            self._current = index
            event.apply(self)
        for element in self.elements:
            element.apply(self)
        return self.lines

    @property
    def step(self) -> int:
        """The step now starting."""
        return self._step

    @property
    def robots(self) -> tuple[RobotInfo, ...]:
        """Every robot as it stands at the start of the step (robots stand still through
        the events phase; taken once a step, when an event first asks)."""
        if self._robots is None:
            self._robots = tuple(robot_info(r) for r in self._team())
        return self._robots

    def _team(self) -> list[Robot]:
        return [a for a in self.agents.values() if isinstance(a, Robot)]

    @property
    def rng(self) -> np.random.Generator:
        """The applying event's own named stream."""
        return self.streams[self._current]

    def fail(
        self, robot: str, part: RobotPart = "robot", factors: tuple[float, float] = (1.0, 1.0)
    ) -> None:
        """Robot ``robot`` loses ``part`` until a matching :meth:`repair`."""
        self._robot(robot).fail(part, factors)

    def repair(
        self, robot: str, part: RobotPart = "robot", factors: tuple[float, float] = (1.0, 1.0)
    ) -> None:
        """Undo one failure of ``part`` of robot ``robot``."""
        self._robot(robot).repair(part, factors)

    def jump(self, robot: str, distance: float) -> None:
        """Throw robot ``robot``'s believed pose ``distance`` cells off."""
        jump_belief(self._robot(robot).features, robot, distance)

    def _robot(self, name: str) -> Robot:
        agent = self.agents[name]
        if not isinstance(agent, Robot):
            raise ValueError(f"{name!r} is not a robot")
        return agent

    def silence(self, agents: Sequence[str], until: int, channels: Channels) -> None:
        """``agents`` neither send nor receive on ``channels`` from now until before ``until``."""
        members = tuple(self.agents[name].index for name in agents)
        self.network.add_blackout(Blackout(self._step, until, members, CHANNELS[channels]))

    def change_world(self, box: Box, occupied: BoolGrid | bool) -> None:
        """Set the true occupancy of ``box``; the explored metric's cells follow."""
        self._follow(self.world.set_cells(box, occupied))

    @property
    def shape(self) -> tuple[int, int]:
        """(rows, cols) of the map."""
        return self.world.shape

    def _follow(self, change: Change) -> None:
        """The explored metric's cells (connected, explorable) follow a change of the truth."""
        if change:
            occupied = self.world.occupied
            follow_world(self.coverage, self.reachable, self.explorable, occupied, [change])

    def change_cells(self, cells: BoolGrid, occupied: bool, crush: Crush) -> list[str]:
        """Make the True cells of ``cells`` rubble or free; robots in the way are spared
        (their cells stay free) or, with ``crush: fail``, buried and failed."""
        robots = self._team()
        under = []
        if occupied:
            rows, cols = np.nonzero(cells)
            centres = np.array([r.position for r in robots], dtype=np.float64).reshape(-1, 2)
            radii = np.array([r.radius for r in robots], dtype=np.float64)
            hit = circles_cover(centres, radii, np.column_stack((rows, cols)))
            under = [r for r, h in zip(robots, hit, strict=True) if h]
            if crush == "avoid" and under:
                cells = cells & ~robot_cells(under, cells.shape)
        self._follow(self.world.set_region(cells, occupied))
        if crush == "fail":
            for robot in under:
                robot.fail("robot")
        return [r.name for r in under]

    def set_door(self, name: str, closed: bool) -> None:
        """Ask door ``name`` to close or open (it closes once nothing is in its way)."""
        self.doors[name].scheduled = closed

    def place_obstacle(
        self,
        name: str,
        footprint: BoolGrid,
        at: tuple[int, int],
        blocks_radio: bool = True,
        over_walls: bool = False,
    ) -> bool:
        """Put or move obstacle ``name`` (False, and nothing changes, if it does not fit)."""
        if self._bodies is None:  # robots stand still through the events phase
            robots = self._team()
            bodies = np.array([(*r.position, r.radius) for r in robots], dtype=np.float64)
            self._bodies = bodies.reshape(-1, 3)
        if not self.world.fits(footprint, at, self._bodies, name, over_walls):
            return False
        if name in self.world.movables:
            self._follow(self.world.move_movable(name, at, footprint))
        else:
            self._follow(self.world.add_movable(name, footprint, at, blocks_radio))
        return True

    def remove_obstacle(self, name: str) -> None:
        """Take obstacle ``name`` off the map."""
        self._follow(self.world.remove_movable(name))

    def log(self, line: str) -> None:
        """Note what happened this step."""
        self.lines.append(line)


def robot_info(robot: Robot) -> RobotInfo:
    """What events may see of ``robot`` now."""
    x, y = robot.position
    broken = tuple(sorted(robot.broken))
    return RobotInfo(robot.name, (x, y), robot.heading, robot.radius, robot.state, broken)


def robot_cells(robots: Sequence[Robot], shape: tuple[int, int]) -> BoolGrid:
    """A map-sized mask of the cells each robot's body overlaps."""
    out = np.zeros(shape, dtype=bool)
    for robot in robots:
        x, y = robot.position
        reach = math.ceil(robot.radius) + 1
        r0, c0 = max(math.floor(y) - reach, 0), max(math.floor(x) - reach, 0)
        rows, cols = np.mgrid[r0 : min(math.floor(y) + reach + 1, shape[0]),
                              c0 : min(math.floor(x) + reach + 1, shape[1])]  # fmt: skip
        dx = np.maximum(np.maximum(cols - x, 0.0), x - (cols + 1))
        dy = np.maximum(np.maximum(rows - y, 0.0), y - (rows + 1))
        out[rows, cols] |= dx * dx + dy * dy < robot.radius**2
    return out
