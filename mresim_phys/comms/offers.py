"""Offers on bounded links (phase 6b): which map cells a sender offers a receiver, in order.

Each ordered pair keeps a queue: the tick up to which the sender's cells have been looked
at for this receiver (``scanned``) and the cells found then that did not fit (the
remainder). An offer is the remainder's cells that are still news to the receiver (a
merge would change its map: :func:`~.changelog.still_news`), with every cell stamped since
``scanned`` that is news (:func:`~.deltas.select_cells`), less the cells already in flight
to it, in the channel's ``priority`` order (``comms/queued.py``). So a long transfer looks
at each cell once, not at the whole backlog every step.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from mresim_phys.agents import Agent
from mresim_phys.comms.changelog import PairGrids, as_row, select_listed, still_news
from mresim_phys.comms.deltas import Cells, select_cells
from mresim_phys.comms.exchange import Edge
from mresim_phys.comms.ledger import NEVER, Ledger
from mresim_phys.comms.send_order import NO_TIER, cut_nearest
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
        since = max(self.scanned.get(edge, NEVER), int(ledger.synced[sender, receiver]))
        grids = PairGrids(
            ledger.stamps[sender], ledger.origins[sender], ledger.copies[sender],
            ledger.copies[receiver], LATEST.state_of(agents[sender].features),
            LATEST.state_of(agents[receiver].features),
        )  # fmt: skip
        rows = grids.rows()
        queued = self.remainder.get(edge, NONE)
        index, codes = still_news(queued, receiver, since, *rows)
        found = self.fresh(edge, since, grids, rows)
        if found is not None:
            fresh, fresh_codes = found
            if len(index):  # disjoint: the queue's cells stamped since are left to these
                index, codes = np.concatenate([index, fresh]), np.concatenate([codes, fresh_codes])
            else:
                index, codes = fresh, fresh_codes
        self.scanned[edge] = tick
        if len(flying):
            keep = ~np.isin(index, flying)
            index, codes = index[keep], codes[keep]
        if len(index) == 0:
            self.remainder.pop(edge, None)
            return None
        seen = None if rows.seen is None else rows.seen[0, index]
        return Cells(index, codes, seen)

    def fresh(
        self, edge: Edge, since: int, grids: PairGrids, rows: PairGrids
    ) -> tuple[IntArray, np.ndarray] | None:
        """The sender's cells stamped after ``since`` that are news to the receiver and did
        not come from it: from the change log, or by scanning the ledger's boxes when the
        log no longer reaches back that far (None: nothing was stamped since)."""
        sender, receiver = edge
        log = self.ledger.log
        listed = None if log is None else log.newer(sender, since)
        if log is not None and listed is not None:
            if len(listed) == 0:
                return None
            marks, mark = log.next_mark(grids.codes.shape)
            return select_listed(listed, receiver, as_row(marks), mark, *rows[1:])
        boxes = compact(self.ledger.newer_boxes(sender, since))
        if len(boxes) == 0:
            return None
        return select_cells(
            boxes, since, receiver, grids.stamps, self.ledger.tiles[sender], grids.origins,
            grids.codes, grids.receiver_codes, False, True, grids.seen, grids.observed,
        )  # fmt: skip

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
        (``priority``; a selection: only which cells make the cut matters)."""
        if count == 0:
            return NONE
        stamps = self.ledger.stamps[sender]
        cols = stamps.shape[1]
        where = agent.believed_position
        if self.priority == "newest":
            ticks = stamps.reshape(-1)[index]
            first: IntArray = np.lexsort((index, squared_distance(index, cols, where), -ticks))
            return first[:count]
        chosen = strategy_point(agent) if self.priority == "strategy" else None
        x, y = chosen or where
        if self.priority == "nearest" or chosen is not None:
            return cut_nearest(index, cols, x, y, count, stamps.reshape(-1), NO_TIER)
        # base_first: what the base lacks (as far as the sender knows) first
        known_upto = int(self.ledger.synced[sender, 0]) if sender != 0 else NEVER
        return cut_nearest(index, cols, x, y, count, stamps.reshape(-1), known_upto)


def squared_distance(index: IntArray, cols: int, where: tuple[float, float]) -> np.ndarray:
    """Squared distance from ``where`` to the centres of the flat cells ``index``."""
    distance: np.ndarray = (index % cols + 0.5 - where[0]) ** 2 + (
        index // cols + 0.5 - where[1]
    ) ** 2
    return distance


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
