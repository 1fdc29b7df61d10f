"""Offers on bounded links (phase 6b): which map cells a sender offers a receiver, in order.

Each ordered pair keeps a queue: the tick up to which the sender's cells have been looked
at for this receiver (``scanned``) and the cells found then that did not fit (the
remainder). An offer is the remainder's cells that are still news to the receiver (a
merge would change its map: :func:`~.deltas.still_news`), with every cell stamped since
``scanned`` that is news (:func:`~.deltas.select_cells`), less the cells already in flight
to it, in the channel's ``priority`` order (``comms/queued.py``). So a long transfer looks
at each cell once, not at the whole backlog every step.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from mresim_phys.agents import Agent
from mresim_phys.comms.deltas import Cells, select_cells, still_news
from mresim_phys.comms.exchange import Edge
from mresim_phys.comms.ledger import Ledger
from mresim_phys.knowledge.latest import LATEST
from mresim_phys.strategies.base import ChoosesSendOrder
from mresim_phys.types import IntArray

NONE = np.zeros(0, dtype=np.int64)


@dataclass
class Offers:
    """Every ordered pair's queue of map cells (module docstring)."""

    ledger: Ledger
    priority: str = "base_first"
    scanned: dict[Edge, int] = field(default_factory=dict)
    remainder: dict[Edge, IntArray] = field(default_factory=dict)

    def cells(
        self, agents: Sequence[Agent], edge: Edge, flying: IntArray, tick: int
    ) -> Cells | None:
        """The cells ``edge``'s sender offers now (in no order: :meth:`split` takes the
        first), ``flying`` those on their way already; the pair's queue is now scanned up
        to ``tick``."""
        sender, receiver = edge
        ledger = self.ledger
        since = max(self.scanned.get(edge, -1), int(ledger.synced[sender, receiver]))
        seen = LATEST.state_of(agents[sender].features)
        observed = LATEST.state_of(agents[receiver].features)
        grids = (ledger.origins[sender], ledger.copies[sender], ledger.copies[receiver])
        index, codes = still_news(self.remainder.get(edge, NONE), receiver, *grids, seen, observed)
        boxes = compact(ledger.newer_boxes(sender, since))
        if len(boxes):
            fresh, fresh_codes = select_cells(
                boxes, since, receiver, ledger.stamps[sender], ledger.tiles[sender],
                grids[0], grids[1], grids[2], False, True, seen, observed,
            )  # fmt: skip
            if len(index):  # the remainder may hold cells stamped again since
                index, codes = np.concatenate([index, fresh]), np.concatenate([codes, fresh_codes])
                index, first = np.unique(index, return_index=True)
                codes = codes[first]
            else:
                index, codes = fresh, fresh_codes
        self.scanned[edge] = tick
        if len(flying):
            keep = ~np.isin(index, flying)
            index, codes = index[keep], codes[keep]
        if len(index) == 0:
            self.remainder.pop(edge, None)
            return None
        return Cells(index, codes, None if seen is None else seen.reshape(-1)[index])

    def split(self, agent: Agent, edge: Edge, cells: Cells, count: int) -> Cells:
        """The ``count`` cells of ``cells`` first in priority order (all of them when they
        fit: their order then does not matter); the rest are kept for the next offer."""
        if count >= len(cells.flat):
            self.keep(edge, NONE)
            return cells
        first = self.first(agent, edge[0], cells.flat, count)
        unsent = np.ones(len(cells.flat), dtype=bool)
        unsent[first] = False
        self.keep(edge, cells.flat[unsent])
        seen = None if cells.seen is None else cells.seen[first]
        return Cells(cells.flat[first], cells.codes[first], seen)

    def synced(self, members: list[int], tick: int) -> None:
        """Every member of a linked group now holds what the others held up to ``tick``
        (every transmission of its tree carried its whole offer, with no latency): the
        ledger syncs every pair of them, and their queues are empty."""
        self.ledger.mark_synced(members, tick)
        group = set(members)
        for edge in [e for e in self.remainder if e[0] in group and e[1] in group]:
            del self.remainder[edge]

    def keep(self, edge: Edge, unsent: IntArray) -> None:
        """The cells of ``edge``'s offer that did not fit: offered again next time."""
        if len(unsent):
            self.remainder[edge] = unsent
        else:
            self.remainder.pop(edge, None)

    def first(self, agent: Agent, sender: int, index: IntArray, count: int) -> IntArray:
        """Positions in ``index`` of the ``count`` cells of ``sender`` sent first
        (``priority``; a partial sort: only which cells make the cut matters)."""
        if count == 0:
            return NONE
        cols = self.ledger.stamps[sender].shape[1]
        where = agent.believed_position
        ticks = self.ledger.stamps[sender].reshape(-1)[index]
        if self.priority == "newest":
            first: IntArray = np.lexsort((index, squared_distance(index, cols, where), -ticks))
            return first[:count]
        if self.priority == "nearest":
            return nearest(index, cols, where, count)
        chosen = strategy_point(agent) if self.priority == "strategy" else None
        if chosen is not None:
            return nearest(index, cols, chosen, count)
        # base_first: what the base lacks (as far as the sender knows) first
        known = ticks <= self.ledger.synced[sender, 0] if sender != 0 else ticks < 0
        lacking, rest = np.flatnonzero(~known), np.flatnonzero(known)
        if len(lacking) >= count:
            return lacking[nearest(index[lacking], cols, where, count)]
        more = rest[nearest(index[rest], cols, where, count - len(lacking))]
        return np.concatenate([lacking, more])


def squared_distance(index: IntArray, cols: int, where: tuple[float, float]) -> np.ndarray:
    """Squared distance from ``where`` to the centres of the flat cells ``index``."""
    distance: np.ndarray = (index % cols + 0.5 - where[0]) ** 2 + (
        index // cols + 0.5 - where[1]
    ) ** 2
    return distance


def nearest(index: IntArray, cols: int, where: tuple[float, float], count: int) -> IntArray:
    """Positions in ``index`` of its ``count`` cells nearest ``where`` (all if fewer)."""
    if count >= len(index):
        return np.arange(len(index))
    cut: IntArray = np.argpartition(squared_distance(index, cols, where), count - 1)[:count]
    return cut


def compact(boxes: np.ndarray) -> np.ndarray:
    """``boxes``, or their bounding box when it is no larger than their areas summed: a
    selection then visits each cell once, with no check against the boxes before it."""
    if len(boxes) < 2:
        return boxes
    areas = (boxes[:, 1] - boxes[:, 0]) * (boxes[:, 3] - boxes[:, 2])
    bound = np.array([[boxes[:, 0].min(), boxes[:, 1].max(), boxes[:, 2].min(), boxes[:, 3].max()]])
    whole = (bound[0, 1] - bound[0, 0]) * (bound[0, 3] - bound[0, 2])
    return bound if whole <= areas.sum() else boxes


def strategy_point(agent: Agent) -> tuple[float, float] | None:
    """The point the agent's strategy sends the cells nearest to first (None: it names
    none, or the agent has no strategy: the base)."""
    strategy = getattr(agent, "strategy", None)
    return strategy.send_first() if isinstance(strategy, ChoosesSendOrder) else None
