"""Knowledge exchange (phase 6b): maps and teammate records travel along links.

Linked agents merge occupancy grids (``np.maximum``: known beats unknown, a cell
seen as obstacle by either stays obstacle), safe space (OR) and teammate records
(the newer report of each agent wins). With 'latest' beliefs (a world that changes)
a cell's value travels with the step it was observed at and the newer observation
wins (equal steps: the obstacle). What travels is counted:

* maps as deltas (:mod:`.ledger`): a transmission carries the cells changed since
  the pair last synchronised, ``CELL_BYTES`` each (a 4-byte cell index and one
  byte of state); ``full`` exchange sends the whole grid every time, one byte
  per cell, for comparison;
* teammate records the receiver does not hold in a newer version, ``RECORD_BYTES``
  each (name, position, goal, state, role and step) plus the size of the payload a
  strategy put in the record (:mod:`mresim_phys.knowledge.teammates`).

With ``multi_hop`` (the default, as the original closes its link table over
chains) each connected group gathers along a breadth-first spanning tree (from
its lowest index: the base station when present) and scatters back, so every
member ends the step with the group's union; on the way back a parent sends a
child only what the child lacks (the parent can tell from the child's upload),
and no agent sends a cell back to the agent its value came from.
Without it, each agent merges what its direct neighbours knew before the phase.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import partial

import numpy as np

from mresim_phys.agents import Agent
from mresim_phys.comms.deltas import Cells, select_cells
from mresim_phys.comms.ledger import Ledger, received_tick, sensed_tick
from mresim_phys.knowledge.known_area import grow_known
from mresim_phys.knowledge.latest import LATEST
from mresim_phys.knowledge.teammates import TeammateInfo

CELL_BYTES = 5
SEEN_BYTES = 4  # per cell with 'latest' beliefs: the step of the value's observation
RunAll = Callable[[Sequence[Callable[[], None]]], object]  # runs every task (any order)
Edge = tuple[int, int]  # (sender, receiver)


def run_in_turn(tasks: Sequence[Callable[[], None]]) -> None:
    """Run ``tasks`` one after another in the calling thread."""
    for task in tasks:
        task()


@dataclass
class Traffic:
    """Bytes sent this step: ``sent[i, j]`` from agent i to agent j, maps and records."""

    sent: np.ndarray
    cells: int = 0
    records: int = 0

    @classmethod
    def empty(cls, n: int) -> Traffic:
        """No traffic among ``n`` agents."""
        return cls(np.zeros((n, n), dtype=np.int64))

    @property
    def total(self) -> int:
        """All bytes sent this step."""
        return int(self.sent.sum())

    def add(
        self, sender: int, receiver: int, cells: int, records: list[TeammateInfo], cell_bytes: int
    ) -> None:
        """Count one transmission: its map cells and the records the receiver took."""
        self.cells += cells
        self.records += len(records)
        record_bytes = sum(r.nbytes() for r in records)
        self.sent[sender, receiver] += cells * cell_bytes + record_bytes


def linked_groups(links: np.ndarray) -> list[list[int]]:
    """Connected groups (two or more agents) of the link graph, each sorted, in index order.

    A link either way joins two agents. A search from each agent not yet grouped, lowest
    first, on the dense matrix: a team's graph is small, and building a sparse matrix for
    ``scipy.sparse.csgraph`` cost more than the search (~0.1 ms a step)."""
    either = links | links.T
    seen = np.zeros(len(links), dtype=bool)
    groups = []
    for first in range(len(links)):
        if seen[first]:
            continue
        seen[first] = True
        members, todo = [first], [first]
        while todo:
            for other in np.flatnonzero(either[todo.pop()] & ~seen).tolist():
                seen[other] = True
                members.append(other)
                todo.append(other)
        if len(members) > 1:
            groups.append(sorted(members))
    return groups


Groups = list[list[int]] | None  # linked groups for multi-hop exchange, None for one hop


def hop_groups(links: np.ndarray, multi_hop: bool) -> Groups:
    """The linked groups knowledge spreads through this step (None: one hop only)."""
    return linked_groups(links) if multi_hop else None


def spanning_tree(links: np.ndarray, root: int) -> list[tuple[int, int]]:
    """(parent, child) edges of a breadth-first tree from ``root``, in visiting order.

    The order of ``scipy.sparse.csgraph.breadth_first_order(..., directed=False)``, which
    it replaced: each agent's links out of it in index order, then those into it."""
    seen = np.zeros(len(links), dtype=bool)
    seen[root] = True
    order, edges = [root], []
    for parent in order:  # grows while it is walked: a breadth-first queue
        for row in (links[parent], links[:, parent]):
            for child in np.flatnonzero(row & ~seen).tolist():
                seen[child] = True
                order.append(child)
                edges.append((parent, child))
    return edges


def depths(tree: list[tuple[int, int]]) -> dict[int, int]:
    """Each tree member's depth (the root's is 0), from (parent, child) edges in visiting
    order (:func:`spanning_tree`)."""
    depth = {tree[0][0]: 0} if tree else {}
    for parent, child in tree:
        depth[child] = depth[parent] + 1
    return depth


def _size(cells: Cells | None) -> int:
    """Map cells in a transmission."""
    return 0 if cells is None else len(cells[0])


def held_records(agent: Agent, step: int) -> list[TeammateInfo]:
    """Every record ``agent`` can send: those it holds and its own."""
    return [*agent.teammates.values(), agent.own_record(step)]


def learn_records(
    receiver: Agent, records: Sequence[TeammateInfo], step: int
) -> list[TeammateInfo]:
    """Keep the records newer than the receiver's, stamped as learned at ``step``; return them."""
    learned = []
    for record in records:
        held = receiver.teammates.get(record.name)
        if record.name != receiver.name and (held is None or record.step > held.step):
            receiver.teammates[record.name] = record.learned_at(step)
            learned.append(record)
    return learned


class Exchange:
    """Moves knowledge along one step's links and counts what it costs."""

    def __init__(self, ledger: Ledger, full_maps: bool = False, maps: bool = True) -> None:
        self.ledger = ledger
        self.full_maps = full_maps
        self.maps = maps

    def run(
        self,
        agents: Sequence[Agent],
        links: np.ndarray,
        step: int,
        groups: Groups,
        run_all: RunAll = run_in_turn,
    ) -> Traffic:
        """Exchange along ``links`` (index 0 = base); return the traffic.

        ``groups`` are the linked groups for multi-hop exchange (:func:`hop_groups`),
        None for one hop per step. ``run_all`` runs a tree level's map transmissions
        (:meth:`share_group`); on threads (``parallel.RobotPool.run_in_chunks``) it ends in the same
        maps, byte for byte.
        """
        traffic = Traffic.empty(len(agents))
        if groups is not None:
            for group in groups:
                self.share_group(agents, links, group, step, traffic, run_all)
        else:
            self.share_direct(agents, links, step, traffic)
        return traffic

    def share_group(
        self,
        agents: Sequence[Agent],
        links: np.ndarray,
        group: list[int],
        step: int,
        traffic: Traffic,
        run_all: RunAll = run_in_turn,
    ) -> None:
        """Gather the group's knowledge up a spanning tree, then scatter it back down.

        Maps and records do not read each other, so the maps move first, a tree level at
        a time (:meth:`gather_maps`, :meth:`scatter_maps`), then the records travel along
        the same transmissions in the tree's order, and each transmission is counted."""
        tree = spanning_tree(links, group[0])
        up = [(child, parent) for parent, child in reversed(tree)]
        down = list(tree)
        cells: dict[Edge, int] = {}
        if self.maps:
            depth = depths(tree)
            self.gather_maps(agents, up, depth, step, cells, run_all)
            self.scatter_maps(agents, down, depth, step, cells, run_all)
            self.ledger.mark_synced(group, received_tick(step))
        for sender, receiver in up + down:
            self.count(agents, sender, receiver, step, traffic, cells.get((sender, receiver), 0))

    def gather_maps(
        self,
        agents: Sequence[Agent],
        up: list[Edge],
        depth: dict[int, int],
        step: int,
        cells: dict[Edge, int],
        run_all: RunAll,
    ) -> None:
        """Children to parents, deepest level first: a level's selections side by side
        (each reads its child, whose own children merged into it a level before), then
        its merges, one task per parent taking its children in the tree's order (a cell
        two children send comes from the first: its origin is the first's)."""
        for level in sorted({depth[s] for s, _ in up}, reverse=True):
            edges = [(s, r) for s, r in up if depth[s] == level]
            picked: dict[Edge, Cells | None] = {}
            run_all([partial(self._pick, agents, edge, picked) for edge in edges])
            parents = list(dict.fromkeys(r for _, r in edges))
            run_all([partial(self._merge_from, agents, p, edges, picked, step) for p in parents])
            cells.update({edge: _size(c) for edge, c in picked.items()})

    def _pick(self, agents: Sequence[Agent], edge: Edge, out: dict[Edge, Cells | None]) -> None:
        """A child's upload: all it has that its parent has not had from it."""
        out[edge] = self.select(agents[edge[0]], agents[edge[1]], only_lacking=False)

    def _merge_from(
        self,
        agents: Sequence[Agent],
        parent: int,
        edges: list[Edge],
        picked: dict[Edge, Cells | None],
        step: int,
    ) -> None:
        """Merge into ``parent`` what its children among ``edges`` picked, in that order."""
        for sender, receiver in edges:
            if receiver == parent:
                self.deliver(agents[parent], picked[sender, receiver], step, sender)

    def scatter_maps(
        self,
        agents: Sequence[Agent],
        down: list[Edge],
        depth: dict[int, int],
        step: int,
        cells: dict[Edge, int],
        run_all: RunAll,
    ) -> None:
        """Parents to children, level by level from the root: each transmission of a level
        reads its parent (complete once the level above is done) and writes its own child,
        so a level's transmissions run side by side; a parent sends what the child lacks."""
        for level in sorted({depth[r] for _, r in down}):
            edges = [(s, r) for s, r in down if depth[r] == level]
            run_all([partial(self._transmit, agents, edge, step, cells) for edge in edges])

    def _transmit(
        self, agents: Sequence[Agent], edge: Edge, step: int, cells: dict[Edge, int]
    ) -> None:
        """A parent's download to a child: what the child lacks; note its size."""
        sender, receiver = edge
        picked = self.select(agents[sender], agents[receiver], only_lacking=True)
        self.deliver(agents[receiver], picked, step, sender)
        cells[edge] = _size(picked)

    def share_direct(
        self, agents: Sequence[Agent], links: np.ndarray, step: int, traffic: Traffic
    ) -> None:
        """One hop only: every linked agent gets what its neighbours knew before the phase."""
        pairs = [(int(i), int(j)) for i, j in np.argwhere(links)]
        packets = {(i, j): self.package(agents[i], agents[j], step) for i, j in pairs}
        for (i, j), (cells, records) in packets.items():
            self.deliver(agents[j], cells, step, i)
            count = _size(cells)
            traffic.add(i, j, count, learn_records(agents[j], records, step), self.cell_bytes)
            if self.maps:
                self.ledger.synced[i, j] = sensed_tick(step)

    @property
    def cell_bytes(self) -> int:
        """Bytes per map cell sent: 1 for whole grids, index + state for deltas."""
        seen = SEEN_BYTES if self.ledger.latest else 0
        return (1 if self.full_maps else CELL_BYTES) + seen

    def send(
        self,
        agents: Sequence[Agent],
        sender: int,
        receiver: int,
        step: int,
        traffic: Traffic,
        only_lacking: bool,
    ) -> None:
        """One transmission of maps and records from ``sender`` to ``receiver``."""
        cells = self.select(agents[sender], agents[receiver], only_lacking)
        self.deliver(agents[receiver], cells, step, sender)
        self.count(agents, sender, receiver, step, traffic, _size(cells))

    def count(
        self,
        agents: Sequence[Agent],
        sender: int,
        receiver: int,
        step: int,
        traffic: Traffic,
        cells: int,
    ) -> None:
        """The records of one transmission (the receiver keeps the newer ones); count it,
        with its ``cells`` map cells."""
        records = learn_records(agents[receiver], held_records(agents[sender], step), step)
        traffic.add(sender, receiver, cells, records, self.cell_bytes)

    def package(
        self, agent: Agent, receiver: Agent, step: int
    ) -> tuple[Cells | None, list[TeammateInfo]]:
        """What ``agent`` sends to ``receiver``, taken before anything is merged."""
        return self.select(agent, receiver, only_lacking=False), held_records(agent, step)

    def select(self, sender: Agent, receiver: Agent, only_lacking: bool) -> Cells | None:
        """The map cells of one transmission (flat indices, cell codes), None without maps."""
        if not self.maps:
            return None
        i, j, ledger = sender.index, receiver.index, self.ledger
        if self.full_maps:
            codes = ledger.copies[i].reshape(-1)
            index = np.arange(codes.size, dtype=np.int64)
            return Cells(index, codes.copy(), seen_of(sender, index))
        boxes = ledger.newer_boxes(i, int(ledger.synced[i, j]))
        if len(boxes) == 0:
            return None
        index, codes = select_cells(
            boxes,
            int(ledger.synced[i, j]),
            j,
            ledger.stamps[i],
            ledger.tiles[i],
            ledger.origins[i],
            ledger.copies[i],
            ledger.copies[j],
            only_lacking,
        )
        return Cells(index, codes, seen_of(sender, index))

    def deliver(self, receiver: Agent, cells: Cells | None, step: int, sender: int) -> None:
        """Merge a transmission's cells into ``receiver``'s grids."""
        deliver(self.ledger, receiver, cells, step, sender)


def deliver(ledger: Ledger, receiver: Agent, cells: Cells | None, step: int, sender: int) -> None:
    """Merge the cells ``sender`` sent into ``receiver``'s grids (and its observation steps,
    with 'latest' beliefs), stamped as received in ``step``: every exchange's last act."""
    if cells is not None and len(cells[0]):
        grids = (receiver.belief, receiver.safe)
        observed = LATEST.state_of(receiver.features)
        changed = ledger.merge(receiver.index, cells, grids, step, sender, observed)
        if changed is not None:
            grow_known(receiver.features, changed)


def seen_of(sender: Agent, index: np.ndarray) -> np.ndarray | None:
    """When the sender's values of cells ``index`` were observed ('latest' beliefs only)."""
    observed = LATEST.state_of(sender.features)
    return None if observed is None else observed.reshape(-1)[index]


def stamp_base_contacts(
    agents: Sequence[Agent], links: np.ndarray, step: int, groups: Groups
) -> None:
    """Stamp ``last_base_contact`` on every agent whose data reached the base this step."""
    if groups is not None:
        reach = next((g for g in groups if g[0] == 0), [])
    else:
        reach = np.flatnonzero(links[0]).tolist()
    for i in reach:
        agents[i].last_base_contact = step
