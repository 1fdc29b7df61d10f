"""Communication contract (phase 6): which agents can talk this step.

A comm model maps the agents' true positions and ranges (and the true world,
read only, for models that look at walls) to a symmetric boolean link matrix
with a false diagonal. Index 0 is the base station, 1..N the robots, as in the
original. Failed robots are masked out by the caller.
"""

from __future__ import annotations

from typing import ClassVar, Protocol, runtime_checkable

import numpy as np
from pydantic import BaseModel, ConfigDict

from ..registry import Registry
from ..types import FloatArray
from ..world import World


class CommParams(BaseModel):
    """Base for comm-model parameters: unknown keys are errors."""

    model_config = ConfigDict(extra="forbid", frozen=True)


@runtime_checkable
class CommModel(Protocol):
    """A communication model: built from its validated params, asked for links each step."""

    name: ClassVar[str]
    Params: ClassVar[type[CommParams]]
    params: CommParams

    def links(self, positions: FloatArray, ranges: FloatArray, world: World) -> np.ndarray:
        """Symmetric (n, n) bool matrix: True where agents i and j can exchange data."""
        ...


COMM_MODELS: Registry[CommModel] = Registry("communication model", "mresim_phys.comm_models")


def pair_distances(positions: FloatArray) -> FloatArray:
    """All-pairs Euclidean distances (n, n).

    >>> pair_distances(np.array([[0.0, 0.0], [3.0, 4.0]]))[0, 1]
    np.float64(5.0)
    """
    delta = positions[:, None, :] - positions[None, :, :]
    return np.hypot(delta[..., 0], delta[..., 1])


def without_self_links(links: np.ndarray) -> np.ndarray:
    """``links`` with the diagonal cleared (no agent links to itself)."""
    np.fill_diagonal(links, False)
    return links
