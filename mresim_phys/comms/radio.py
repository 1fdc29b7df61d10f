"""Radio links (phase 6, links): what a channel's radio adds to its comm model.

A :class:`LinkLayer` takes a channel's links as the model and the dropout give them and
applies, in this order, each option the scenario turned on (docs/communication.md,
"Radio links"):

1. shadowing and fast fading (:mod:`.shadowing`), added to the signal of a model that has
   one (``pair_signals`` and a ``cutoff_dbm``: ``path_loss``): the link holds when the
   weaker direction's signal plus the pair's shadowing and fading is at or above the
   cut-off; every pair is checked, since shadowing may carry a link past the model's reach;
2. burst losses (:mod:`.bursts`);
3. a loss table of measured loss against wall count and distance (:mod:`.traces`);
4. a replayed trace (:mod:`.traces`), which may force a pair up or down and set its capacity.

A failed or silenced agent stays silent whatever an option says.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from mresim_phys.comms.base import Radios, pair_distances, without_self_links
from mresim_phys.comms.bursts import GilbertElliott
from mresim_phys.comms.radio_params import RadioSpec
from mresim_phys.comms.shadowing import Shadowing
from mresim_phys.comms.traces import LinkTrace, LossTable, loss_rows, trace_rows
from mresim_phys.types import FloatArray, IntArray
from mresim_phys.world.space import World
from mresim_phys.world.walls import walls_between


@runtime_checkable
class SignalModel(Protocol):
    """A comm model with a received signal in dB: shadowing and fading add to it."""

    def pair_signals(
        self, radios: Radios, world: World, rows: IntArray, cols: IntArray
    ) -> FloatArray:
        """The weaker direction's signal (dBm) of each pair (rows[k], cols[k])."""
        ...

    @property
    def cutoff_dbm(self) -> float:
        """The weakest signal that still links."""
        ...


@dataclass
class LinkLayer:
    """One channel's radio options among ``n`` agents (index 0 the base)."""

    spec: RadioSpec
    n: int
    shadowing: Shadowing | None = None
    bursts: GilbertElliott | None = None
    table: LossTable | None = None
    trace: LinkTrace | None = None

    def model_links(self, model: object, radios: Radios, world: World) -> np.ndarray | None:
        """The links with shadowing and fading (None: no shadowing, the model's own)."""
        if self.shadowing is None or not isinstance(model, SignalModel):
            return None
        rows, cols = np.triu_indices(len(radios), k=1)
        signal = model.pair_signals(radios, world, rows, cols)
        signal = signal + self.shadowing.pair_db(radios.positions, rows, cols)
        signal = signal + self.shadowing.fading_db(len(rows))
        keep = signal >= model.cutoff_dbm
        links = np.zeros((len(radios), len(radios)), dtype=bool)
        links[rows[keep], cols[keep]] = links[cols[keep], rows[keep]] = True
        return without_self_links(links)

    def apply(
        self, links: np.ndarray, radios: Radios, world: World, speaking: np.ndarray, step: int
    ) -> np.ndarray:
        """``links`` after bursts, the loss table and the trace (module docstring)."""
        if self.bursts is not None:
            links = links & ~self.bursts.lost(len(links))
        if self.table is not None:
            links = links & ~self.table_losses(links, radios, world)
        if self.trace is not None:
            links = self.trace.apply(links, speaking, step)
        return links

    def table_losses(self, links: np.ndarray, radios: Radios, world: World) -> np.ndarray:
        """This step's losses by the loss table (a draw for every pair, every step)."""
        assert self.table is not None
        rows, cols = np.triu_indices(len(links), k=1)
        draw = self.table.rng.random(len(rows))
        linked = np.flatnonzero(links[rows, cols])
        lost = np.zeros_like(links)
        if len(linked) == 0:
            return lost
        r, c = rows[linked], cols[linked]
        positions = radios.positions
        walls, _ = walls_between(world.radio_occupied, positions[r], positions[c])
        loss = self.table.loss(walls, pair_distances(positions)[r, c])
        hit = draw[linked] < loss
        lost[r[hit], c[hit]] = lost[c[hit], r[hit]] = True
        return lost

    @property
    def bounded(self) -> bool:
        """Whether a link's capacity or latency limits what it carries (a trace may set
        capacities)."""
        return self.spec.bounded or (self.trace is not None and self.trace.has_capacity)

    def capacity(self, sender: int, receiver: int) -> int | None:
        """Bytes per step the link ``sender`` -> ``receiver`` carries (None: unlimited)."""
        if self.trace is not None and self.trace.capacity[sender, receiver] >= 0:
            return int(self.trace.capacity[sender, receiver])
        return self.spec.capacity


def build_layer(
    spec: RadioSpec,
    channel: str,
    names: Sequence[str],
    shape: tuple[int, int],
    stream: Callable[[str], np.random.Generator],
) -> LinkLayer | None:
    """The radio of ``channel`` (``main`` or ``control``) among agents ``names`` on a map
    of ``shape``; its random streams are ``<option>-<channel>``. None: no option is on."""
    if not (spec.lossy or spec.bounded):
        return None
    n = len(names)
    layer = LinkLayer(spec, n)
    if spec.shadowing is not None:
        layer.shadowing = Shadowing.build(
            spec.shadowing, shape, stream(f"shadowing-{channel}"), stream(f"fading-{channel}")
        )
    if spec.bursts is not None:
        layer.bursts = GilbertElliott(spec.bursts, n, stream(f"bursts-{channel}"))
    if spec.loss_table is not None:
        layer.table = LossTable(loss_rows(spec.loss_table), stream(f"loss-{channel}"))
    if spec.trace is not None:
        layer.trace = LinkTrace(trace_rows(spec.trace, names), n, stream(f"trace-{channel}"))
    return layer
