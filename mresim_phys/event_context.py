"""Events phase (phase 0 of a step): the context through which events act on a run.

:class:`RunEventContext` implements :class:`~mresim_phys.world.events.EventContext`
over the running simulation's parts: robots fail (whole or one part), agents
fall silent through the network's blackouts, the true world changes (the
coverage counter's reachable set follows), lines are logged for the step, and
each event draws only from its own named random stream.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from mresim_phys.agents import Agent, Robot
from mresim_phys.comms.network import Blackout, Network
from mresim_phys.knowledge.mapping import Coverage
from mresim_phys.types import BoolGrid
from mresim_phys.world.events import Box, Channels, Event, RobotPart
from mresim_phys.world.reach import Reachable, follow_changes
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
        reachable: Reachable,
        streams: Sequence[np.random.Generator],
    ) -> None:
        self.agents = {a.name: a for a in agents}
        self.network, self.world, self.coverage = network, world, coverage
        self.reachable = reachable
        self.streams = list(streams)
        self.lines: list[str] = []
        self._step = 0
        self._current = 0

    def run(self, events: Sequence[Event], step: int) -> list[str]:
        """Apply every event (in scenario order) at ``step``; return the lines they logged."""
        self._step, self.lines = step, []
        for index, event in enumerate(events):
            self._current = index
            event.apply(self)
        return self.lines

    @property
    def step(self) -> int:
        """The step now starting."""
        return self._step

    @property
    def rng(self) -> np.random.Generator:
        """The applying event's own named stream."""
        return self.streams[self._current]

    def fail(self, robot: str, part: RobotPart = "robot") -> None:
        """Robot ``robot`` loses ``part`` for good."""
        agent = self.agents[robot]
        if not isinstance(agent, Robot):
            raise ValueError(f"{robot!r} is not a robot")
        agent.fail(part)

    def silence(self, agents: Sequence[str], until: int, channels: Channels) -> None:
        """``agents`` neither send nor receive on ``channels`` from now until before ``until``."""
        members = tuple(self.agents[name].index for name in agents)
        self.network.add_blackout(Blackout(self._step, until, members, CHANNELS[channels]))

    def change_world(self, box: Box, occupied: BoolGrid | bool) -> None:
        """Set the true occupancy of ``box``; the explored metric's reachable set follows."""
        change = self.world.set_cells(box, occupied)
        if change:
            follow_changes(self.coverage, self.reachable, self.world.occupied, [change])

    def log(self, line: str) -> None:
        """Note what happened this step."""
        self.lines.append(line)
