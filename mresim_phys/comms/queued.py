"""Bounded links (phase 6b): knowledge that queues behind a link's capacity and arrives late.

With a ``capacity`` (bytes per step each way on a link), a ``radio_capacity`` (bytes per
step an agent's radio sends over all its links) or a ``latency`` (steps per hop), a
transmission no longer carries everything at once. Each step, along the same edges the
unbounded exchange uses (the spanning tree of each linked group, children to parents then
parents to children; with ``multi_hop: false`` every linked ordered pair), a sender offers:

1. the teammate records the receiver holds in no newer version, its own first, then the
   newest (records, payloads and the control channel go first);
2. the map cells stamped since the pair last synchronised that would change the
   receiver's map (an idealised acknowledgement: a cell the receiver holds is never sent
   again), not from the receiver and not already in flight to it, in the channel's
   ``priority`` order: ``base_first`` (cells the base lacks, as far as the sender's ledger
   knows, then the rest; each nearest the sender first), ``nearest`` or ``newest``.

It sends the longest prefix that fits the link's and the radio's bytes left this step;
the rest stays queued (offered again next step, re-ordered; a transfer a broken link cut
resumes at the next contact). A packet arrives ``latency`` steps after it was sent,
whether or not the link still holds (it has left the radio), and is merged then; the
ledger records a pair as synchronised only when a packet that carried the whole offer
arrives, so it never counts as delivered a cell that has not arrived. With latency 0
a packet arrives at once, so within a step knowledge crosses as many hops as the
capacities allow; with latency d it crosses one hop per d steps (store and forward).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from mresim_phys.agents import Agent
from mresim_phys.comms.deltas import Cells
from mresim_phys.comms.exchange import (
    CELL_BYTES,
    SEEN_BYTES,
    Edge,
    Groups,
    RunAll,
    Traffic,
    deliver,
    learn_records,
    run_in_turn,
    spanning_tree,
)
from mresim_phys.comms.ledger import Ledger, received_tick, sensed_tick
from mresim_phys.comms.offers import Offers
from mresim_phys.comms.radio import LinkLayer
from mresim_phys.comms.radio_feature import RADIO, RadioLoadValue
from mresim_phys.knowledge.teammates import TeammateInfo
from mresim_phys.types import IntArray


@dataclass
class Packet:
    """One transmission on its way: what it carries, its size, when it lands and the sync
    tick it completes (None: part of the offer stayed queued)."""

    arrive: int
    sender: int
    receiver: int
    cells: Cells | None
    records: list[TeammateInfo]
    nbytes: int
    sync: int | None


@dataclass
class RadioLoad:
    """Bytes per agent in one step: offered, sent, delivered (its packets that landed, by
    sender) and delivered to the base."""

    offered: IntArray
    sent: IntArray
    delivered: IntArray
    to_base: IntArray

    @classmethod
    def empty(cls, n: int) -> RadioLoad:
        """No load among ``n`` agents."""
        return cls(*(np.zeros(n, dtype=np.int64) for _ in range(4)))


@dataclass
class QueuedExchange:
    """Moves knowledge along bounded links (module docstring) and counts what it costs."""

    ledger: Ledger
    layer: LinkLayer
    maps: bool = True
    flight: list[Packet] = field(default_factory=list)
    offers: Offers = field(init=False)
    load: RadioLoad = field(default_factory=lambda: RadioLoad.empty(0))
    base_changed: bool = False  # a packet landed at the base this step
    tree: bool = True  # this step's edges are spanning trees (multi-hop)
    own: dict[int, TeammateInfo] = field(default_factory=dict)  # this step's own records

    def __post_init__(self) -> None:
        self.offers = Offers(self.ledger, self.layer.spec.priority)
        self.ledger.keep_log()

    @property
    def cell_bytes(self) -> int:
        """Bytes per map cell sent: index and state, and the observation step if 'latest'."""
        return CELL_BYTES + (SEEN_BYTES if self.ledger.latest else 0)

    def run(
        self,
        agents: Sequence[Agent],
        links: np.ndarray,
        step: int,
        groups: Groups,
        run_all: RunAll = run_in_turn,
    ) -> Traffic:
        """This step's transmissions along ``links``; return the traffic sent. One at a time
        (``run_all`` is not used: each transmission reads what the one before delivered)."""
        n = len(agents)
        traffic, self.load = Traffic.empty(n), RadioLoad.empty(n)
        self.base_changed, self.tree = False, groups is not None
        self.own.clear()
        self.land(agents, step)
        left = np.full(n, np.iinfo(np.int64).max, dtype=np.int64)
        if self.layer.spec.radio_capacity is not None:
            left[:] = self.layer.spec.radio_capacity
        for members, edges in edges_of(links, groups):
            whole = [self.send(agents, edge, step, left, traffic) for edge in edges]
            if members and self.layer.spec.latency == 0:
                for part in whole_parts(members, edges, whole):
                    self.offers.synced(part, self.sync_tick(step))
        self.land(agents, step)
        self.publish(agents)
        return traffic

    def send(
        self, agents: Sequence[Agent], edge: Edge, step: int, left: IntArray, traffic: Traffic
    ) -> bool:
        """One transmission along ``edge``; whether it carried the whole offer of cells. On
        a tree what lands travels on at once (latency 0)."""
        packet = self.pack(agents, edge[0], edge[1], step, left)
        if packet is None:
            return edge not in self.offers.remainder
        cells = 0 if packet.cells is None else len(packet.cells.flat)
        traffic.add(edge[0], edge[1], cells, packet.records, self.cell_bytes)
        self.flight.append(packet)
        if self.tree:
            self.land(agents, step)
        return packet.sync is not None or not self.maps

    def publish(self, agents: Sequence[Agent]) -> None:
        """Write this step's load into each robot's ``radio`` feature (if it has one)."""
        load = self.load
        for agent in agents:
            counters = RADIO.state_of(agent.features)
            if counters is not None:
                i = agent.index
                counters.value = RadioLoadValue(
                    int(load.offered[i]), int(load.sent[i]), int(load.delivered[i]),
                    int(load.to_base[i]),
                )  # fmt: skip

    def land(self, agents: Sequence[Agent], step: int) -> None:
        """Merge every packet due by ``step``, in the order sent."""
        due = [p for p in self.flight if p.arrive <= step]
        if not due:
            return
        self.flight = [p for p in self.flight if p.arrive > step]
        for packet in due:
            receiver = agents[packet.receiver]
            if not receiver.speaking:  # a receiver that failed or lost its radio meanwhile
                continue
            deliver(self.ledger, receiver, packet.cells, step, packet.sender)
            learn_records(receiver, packet.records, step)
            if packet.sync is not None:
                synced = self.ledger.synced
                pair = packet.sender, packet.receiver
                synced[pair] = max(int(synced[pair]), packet.sync)
            self.load.delivered[packet.sender] += packet.nbytes
            if packet.receiver == 0:
                self.load.to_base[packet.sender] += packet.nbytes
                self.base_changed = True

    def pack(
        self, agents: Sequence[Agent], sender: int, receiver: int, step: int, left: IntArray
    ) -> Packet | None:
        """The packet ``sender`` sends ``receiver`` now: the offer's longest prefix that fits
        the link's capacity and the radio's bytes ``left`` (updated); None: nothing to send."""
        records = self.offered_records(agents, sender, receiver, step)
        edge = (sender, receiver)
        cells = (
            self.offers.cells(agents, edge, self.flying(edge), self.sync_tick(step))
            if self.maps
            else None
        )
        record_bytes = [r.nbytes() for r in records]
        cell_count = 0 if cells is None else len(cells.flat)
        offer = sum(record_bytes) + cell_count * self.cell_bytes
        if offer == 0:
            return None
        capacity = self.layer.capacity(sender, receiver)
        room = int(left[sender]) if capacity is None else min(int(left[sender]), capacity)
        taken_records = fitting(record_bytes, room)
        room -= sum(record_bytes[:taken_records])
        taken_cells = min(cell_count, room // self.cell_bytes)
        nbytes = sum(record_bytes[:taken_records]) + taken_cells * self.cell_bytes
        self.load.offered[sender] += offer
        self.load.sent[sender] += nbytes
        left[sender] -= nbytes
        part = (
            None if cells is None else self.offers.split(agents[sender], edge, cells, taken_cells)
        )
        whole = self.maps and taken_cells == cell_count
        sync = self.offers.scanned.get(edge) if whole else None
        if nbytes == 0:
            return None
        arrive = step + self.layer.spec.latency
        return Packet(arrive, sender, receiver, part, records[:taken_records], nbytes, sync)

    def sync_tick(self, step: int) -> int:
        """The tick a whole offer made now brings its pair up to. Everything the sender
        holds is stamped at most ``received_tick(step)``; that tick is safe when nothing
        the receiver lacks can reach the sender later in the step: on a spanning tree
        with no latency the sender hears afterwards only from the receiver itself (values
        that came from it are never sent back), and with a latency every packet of the
        step has landed before the first is packed. With one hop and no latency (packets
        land after all are packed) or 'latest' beliefs, the sensed tick."""
        tree_or_late = self.tree or self.layer.spec.latency > 0
        return received_tick(step) if tree_or_late and not self.ledger.latest else sensed_tick(step)

    def flying(self, edge: Edge) -> IntArray:
        """The map cells on their way along ``edge``."""
        cells = [
            p.cells.flat
            for p in self.flight
            if (p.sender, p.receiver) == edge and p.cells is not None
        ]
        return np.concatenate(cells) if cells else np.zeros(0, dtype=np.int64)

    def offered_records(
        self, agents: Sequence[Agent], sender: int, receiver: int, step: int
    ) -> list[TeammateInfo]:
        """The records the receiver holds in no newer version and that are not on their
        way to it: the sender's own first, then the newest."""
        known, name = agents[receiver].teammates, agents[receiver].name
        flying = {
            (r.name, r.step)
            for p in self.flight
            if (p.sender, p.receiver) == (sender, receiver)
            for r in p.records
        }

        def offered(r: TeammateInfo) -> bool:
            held = known.get(r.name)
            return (
                r.name != name
                and (held is None or held.step < r.step)
                and (r.name, r.step) not in flying
            )

        held = [r for r in agents[sender].teammates.values() if offered(r)]
        held.sort(key=lambda r: (-r.step, r.name))
        own = self.own.get(sender)
        if own is None:  # one per agent and step: nothing it reports changes in the phase
            own = self.own[sender] = agents[sender].own_record(step)
        return [own, *held] if offered(own) else held


def fitting(sizes: Sequence[int], room: int) -> int:
    """How many of ``sizes``, in order, fit in ``room`` bytes (the first that does not
    fit ends the prefix)."""
    total = 0
    for count, size in enumerate(sizes):
        if total + size > room:
            return count
        total += size
    return len(sizes)


def whole_parts(members: list[int], edges: list[Edge], whole: list[bool]) -> list[list[int]]:
    """The parts of a group's tree joined by links that carried their whole offers both
    ways this step. With no latency every member of a part then holds what any other
    held (the part's top gathered it on the way up and gave it back on the way down), so
    the whole part is synchronised, as the unbounded exchange synchronises a group."""
    ok = {edge for edge, done in zip(edges, whole, strict=True) if done}
    parent = {m: m for m in members}

    def root(m: int) -> int:
        while parent[m] != m:
            m = parent[m]
        return m

    for a, b in ok:
        if a < b and (b, a) in ok:
            parent[root(a)] = root(b)
    parts: dict[int, list[int]] = {}
    for m in members:
        parts.setdefault(root(m), []).append(m)
    return [sorted(p) for p in parts.values() if len(p) > 1]


def edges_of(links: np.ndarray, groups: Groups) -> list[tuple[list[int], list[Edge]]]:
    """The step's transmissions by group: each group's members and its spanning tree's
    edges up then down (multi-hop), or no members and every linked ordered pair (one hop)."""
    if groups is None:
        return [([], [(int(i), int(j)) for i, j in np.argwhere(links)])]
    out = []
    for group in groups:
        tree = spanning_tree(links, group[0])
        out.append((group, [(child, parent) for parent, child in reversed(tree)] + tree))
    return out
