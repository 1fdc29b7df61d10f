"""Communication contract (phase 6): which agents can talk this step.

A comm model maps the agents' radios (true positions, ranges and transmit
powers) and the true world (read only, for models that look at walls) to a
symmetric boolean link matrix with a false diagonal. Index 0 is the base
station, 1..N the robots, as in the original. Failed robots, blackouts and
dropouts are applied by the caller (``comms/network.py``).

A model also answers :meth:`CommModel.reach`: how far, along each of a set of
directions, an agent's signal carries. Renderers draw that polygon as the
agent's communication region (the original's GUI range polygon).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, Protocol, runtime_checkable

import numpy as np

from mresim_phys.comms.params import CommParams
from mresim_phys.types import FloatArray, IntArray
from mresim_phys.world.space import World


@dataclass(frozen=True)
class Radios:
    """The radios of n agents: where they are and what each transmits.

    ``ranges`` are the agents' comm ranges (cells): the disk radius for ``disk``
    and ``line_of_sight``, the reference distance for ``path_loss``. ``powers``
    are signal strengths at that distance (dBm), NaN where the model's default applies.
    """

    positions: FloatArray
    ranges: FloatArray
    powers: FloatArray

    @classmethod
    def of(cls, positions: object, ranges: object, powers: object = None) -> Radios:
        """Radios from array-likes; ``powers`` None means every agent uses the default."""
        where = np.asarray(positions, dtype=float).reshape(-1, 2)
        reach = np.asarray(ranges, dtype=float).reshape(-1)
        power = np.full(len(reach), np.nan) if powers is None else np.asarray(powers, float)
        return cls(where, reach, power.reshape(-1))

    def __len__(self) -> int:
        return len(self.ranges)


@runtime_checkable
class CommModel(Protocol):
    """A communication model: built from its validated params, asked for links each step."""

    name: ClassVar[str]
    Params: ClassVar[type[CommParams]]

    @property
    def params(self) -> CommParams:
        """The validated parameters it was built from (read only: a model may narrow it)."""
        ...

    def links(self, radios: Radios, world: World) -> np.ndarray:
        """Symmetric (n, n) bool matrix: True where agents i and j can exchange data."""
        ...

    def reach(self, radios: Radios, index: int, angles: FloatArray, world: World) -> FloatArray:
        """Per direction, how far from agent ``index`` a receiver still hears it (cells)."""
        ...


def pair_distances(positions: FloatArray) -> FloatArray:
    """All-pairs Euclidean distances (n, n).

    >>> pair_distances(np.array([[0.0, 0.0], [3.0, 4.0]]))[0, 1]
    np.float64(5.0)
    """
    delta = positions[:, None, :] - positions[None, :, :]
    return np.hypot(delta[..., 0], delta[..., 1])


def candidate_pairs(positions: FloatArray, reach: FloatArray) -> tuple[IntArray, IntArray]:
    """Index pairs i < j closer than ``reach[i, j]``: the only pairs worth a wall check."""
    rows, cols = np.triu_indices(len(positions), k=1)
    near = pair_distances(positions)[rows, cols] < reach[rows, cols]
    return rows[near], cols[near]


def symmetric_links(n: int, rows: IntArray, cols: IntArray) -> np.ndarray:
    """The (n, n) link matrix holding exactly the pairs (rows[k], cols[k]), both ways."""
    links = np.zeros((n, n), dtype=bool)
    links[rows, cols] = links[cols, rows] = True
    return without_self_links(links)


def without_self_links(links: np.ndarray) -> np.ndarray:
    """``links`` with the diagonal cleared (no agent links to itself)."""
    np.fill_diagonal(links, False)
    return links
