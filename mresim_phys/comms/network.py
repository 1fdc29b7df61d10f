"""The communication phase (phase 6): links on two channels, then the exchange.

Each step, for every channel, the channel's model gives the links among alive
agents from their true positions and the true walls; scheduled blackouts silence
agents; an optional per-link loss probability drops links at random (one draw
per agent pair and step from the channel's named random stream, so the same seed
drops the same links whatever else happens). Then knowledge moves:

* the **main** channel carries maps (as deltas, :mod:`.ledger`) and teammate records;
* the optional **control** channel (long range, low bandwidth: the paper's future
  work 2) carries teammate records only: positions, goals, roles, states.

Both relay along chains of linked agents within the step when ``multi_hop`` is
on. What was sent is counted in bytes (:class:`~.exchange.Traffic`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import partial

import numpy as np

from mresim_phys.agents import Agent, Robot
from mresim_phys.comms.base import CommModel, Radios
from mresim_phys.comms.exchange import (
    Exchange,
    RunAll,
    Traffic,
    hop_groups,
    run_in_turn,
    stamp_base_contacts,
)
from mresim_phys.comms.ledger import Ledger, box_around
from mresim_phys.comms.queued import QueuedExchange
from mresim_phys.comms.radio import LinkLayer
from mresim_phys.planning.grid import Box
from mresim_phys.types import FloatArray
from mresim_phys.world.space import World


@dataclass(frozen=True)
class Blackout:
    """Agents ``members`` are silent on ``channels`` from step ``start`` until before ``until``."""

    start: int
    until: int
    members: tuple[int, ...]
    channels: tuple[str, ...] = ("main", "control")

    def silences(self, step: int, channel: str) -> bool:
        """Whether this blackout is on at ``step`` for ``channel``."""
        return self.start <= step < self.until and channel in self.channels


@dataclass
class Channel:
    """One radio channel: a comm model, the agents' radios on it, and its link losses."""

    name: str
    model: CommModel
    ranges: FloatArray
    powers: FloatArray
    dropout: float = 0.0
    rng: np.random.Generator = field(default_factory=lambda: np.random.default_rng(0))
    radio: LinkLayer | None = None  # the radio options the scenario turned on

    def radios(self, agents: Sequence[Agent]) -> Radios:
        """The agents' radios on this channel at their current positions."""
        return Radios(np.array([a.position for a in agents], dtype=float), self.ranges, self.powers)

    def links(
        self, agents: Sequence[Agent], world: World, silent: np.ndarray, step: int = 0
    ) -> np.ndarray:
        """This step's links: the model's (with shadowing and fading), among alive and
        unsilenced agents, minus dropouts, then the radio's losses and trace (:mod:`.radio`)."""
        speaking = np.array([a.speaking for a in agents]) & ~silent
        radios = self.radios(agents)
        found = None if self.radio is None else self.radio.model_links(self.model, radios, world)
        model_links = self.model.links(radios, world) if found is None else found
        links: np.ndarray = model_links & np.outer(speaking, speaking)
        kept: np.ndarray = links & ~self.dropped(len(agents))
        if self.radio is not None:
            kept = self.radio.apply(kept, radios, world, speaking, step)
        return kept

    def dropped(self, n: int) -> np.ndarray:
        """Symmetric matrix of the links lost this step (drawn every step for every pair)."""
        lost = np.zeros((n, n), dtype=bool)
        if self.dropout <= 0:
            return lost
        rows, cols = np.triu_indices(n, k=1)
        draw = self.rng.random(len(rows)) < self.dropout
        lost[rows[draw], cols[draw]] = lost[cols[draw], rows[draw]] = True
        return lost


def exchange_of(
    channel: Channel | None, ledger: Ledger, *, full_maps: bool = False, maps: bool = True
) -> Exchange | QueuedExchange:
    """The exchange of ``channel``: queued when its radio bounds what a link carries."""
    radio = None if channel is None else channel.radio
    if radio is not None and radio.bounded:
        return QueuedExchange(ledger, radio, maps=maps)
    return Exchange(ledger, full_maps=full_maps, maps=maps)


@dataclass(frozen=True)
class CommRecord:
    """What the communication phase did in one step."""

    links: np.ndarray
    control_links: np.ndarray
    traffic: Traffic
    control_traffic: Traffic


class Network:
    """Runs the communication phase for a fixed set of agents (index 0 = base)."""

    def __init__(
        self,
        main: Channel,
        ledger: Ledger,
        *,
        control: Channel | None = None,
        multi_hop: bool = True,
        full_maps: bool = False,
    ) -> None:
        self.main, self.control = main, control
        self.ledger = ledger
        self.blackouts: tuple[Blackout, ...] = ()  # added by blackout events as they start
        self.multi_hop = multi_hop
        self.maps = exchange_of(main, ledger, full_maps=full_maps)
        self.records = exchange_of(control, ledger, maps=False)

    @property
    def bounded(self) -> bool:
        """Whether the main channel's links are bounded (``comms/queued.py``)."""
        return isinstance(self.maps, QueuedExchange)

    @property
    def base_received(self) -> bool:
        """Whether a packet landed at the base in this step's exchange on bounded links
        (the base's map may change while it is linked to no one)."""
        return isinstance(self.maps, QueuedExchange) and self.maps.base_changed

    def idle(self, n: int) -> CommRecord:
        """The record of a step in which nothing was linked or sent."""
        none = np.zeros((n, n), dtype=bool)
        return CommRecord(none, none.copy(), Traffic.empty(n), Traffic.empty(n))

    def add_blackout(self, blackout: Blackout) -> None:
        """Silence ``blackout.members`` on its channels from its start until before its end."""
        self.blackouts = (*self.blackouts, blackout)

    def note_scan(self, index: int, box: Box) -> None:
        """Agent ``index``'s own map may have changed inside ``box``."""
        self.ledger.note(index, box)

    def silent(self, n: int, step: int, channel: str) -> np.ndarray:
        """Which of ``n`` agents a blackout silences at ``step`` on ``channel``."""
        silent = np.zeros(n, dtype=bool)
        for blackout in self.blackouts:
            if blackout.silences(step, channel):
                silent[list(blackout.members)] = True
        return silent

    def stamp_own(self, robot: Robot, window: Box | None, step: int) -> None:
        """Stamp in the ledger the cells ``robot`` changed itself this step: inside
        ``window`` (the union of its scans' windows, None: it did not scan) and next to its
        body (a bump marks a cell outside any scan). It touches only the robot's own rows
        and arrays of the ledger, so robots' tasks call it on threads (``sim.py``)."""
        if window is not None:
            self.ledger.note(robot.index, window)
        self.note_body(robot)
        self.ledger.stamp_sensed(robot.index, robot.belief, robot.safe, step)

    def note_body(self, robot: Robot) -> None:
        """``robot``'s map may have changed next to its body: a bump marks a cell there
        outside any scan."""
        shape = self.ledger.stamps[robot.index].shape
        self.ledger.note(robot.index, box_around(robot.believed_position, robot.radius + 2, shape))

    def communicate(
        self,
        agents: Sequence[Agent],
        world: World,
        step: int,
        run_all: RunAll = run_in_turn,
        stamped: frozenset[int] = frozenset(),
    ) -> CommRecord:
        """Find this step's links and move knowledge along them.

        First each agent's own changes of the step are stamped in its ledger, but for the
        agents (indices) ``stamped`` already (:meth:`stamp_own`); each stamp touches only
        its agent's arrays and rows, so ``run_all`` may run them on threads:
        ``parallel.RobotPool.run``."""
        ledger = self.ledger
        run_all(
            [
                partial(ledger.stamp_sensed, a.index, a.belief, a.safe, step)
                for a in agents
                if a.index not in stamped
            ]
        )
        n = len(agents)
        links = self.main.links(agents, world, self.silent(n, step, "main"), step)
        groups = hop_groups(links, self.multi_hop)
        traffic = self.maps.run(agents, links, step, groups, run_all)
        stamp_base_contacts(agents, links, step, groups)
        control_links = np.zeros_like(links)
        control_traffic = Traffic.empty(n)
        if self.control is not None:
            control_links = self.control.links(agents, world, self.silent(n, step, "control"), step)
            control_groups = hop_groups(control_links, self.multi_hop)
            control_traffic = self.records.run(agents, control_links, step, control_groups)
        return CommRecord(links, control_links, traffic, control_traffic)
