"""Snapshots (phase 8 input): the state of a run at the end of a step, as views see it.

A :class:`Snapshot` is everything the renderer, the video recorder and the run
log need, and nothing they must not touch: positions, headings, states, paths,
goals, links, the truth and its version, and every agent's belief grid
(read-only views, not copies). ``Simulation.snapshot()`` builds one from a live
run; ``output.runlog`` logs every field of it and rebuilds equal snapshots from
the log (``output.logformat`` says how each field is stored), so a replayed frame
equals the live one.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
from numpy.typing import NDArray

from mresim_phys.types import BeliefGrid, BoolGrid, FloatArray, RobotSight

if TYPE_CHECKING:
    from mresim_phys.meeting_board import MeetingBoard


def read_only(array: np.ndarray) -> np.ndarray:
    """A read-only view of ``array``."""
    view: np.ndarray = array.view()
    view.flags.writeable = False
    return view


def bool_view(grid: Any) -> BoolGrid | None:
    """``grid`` as a read-only bool grid (no copy if it is one already); None stays None."""
    return None if grid is None else read_only(np.asarray(grid, dtype=bool))


def points_or_none(points: Any) -> FloatArray | None:
    """``points`` as a (k, 2) float64 array; None stays None."""
    return None if points is None else np.asarray(points, dtype=np.float64).reshape(-1, 2)


@dataclass(frozen=True)
class AgentSnapshot:
    """One agent (base station or robot) at the end of a step."""

    name: str
    kind: str  # "base" or "robot"
    position: tuple[float, float]
    heading: float
    radius: float
    state: str  # active / error / done / failed (the base: "base")
    role: str
    comm_range: float
    belief: BeliefGrid
    safe: BoolGrid
    path: FloatArray = field(default_factory=lambda: np.zeros((0, 2)))
    goal: tuple[float, float] | None = None
    distance: float = 0.0
    parent: str | None = None
    skeleton: BoolGrid | None = None  # from a strategy's Decision.info["skeleton"], if any
    rendezvous: FloatArray | None = None  # (k, 2) points from Decision.info["rendezvous"]
    rv_candidates: FloatArray | None = None  # (k, 2) potential rendezvous points (info)
    rv_through_walls: FloatArray | None = None  # (k, 2) points linked through walls (info)
    base_contact: int = -1  # last step this agent's data reached the base (-1: never)
    features: Mapping[str, Any] = field(default_factory=dict)  # each feature's value (features.py)
    given_up: BoolGrid | None = None  # frontier cells its strategy tried in vain, gave up


@dataclass(frozen=True)
class CommSummary:
    """What the communication phase did in a step, beyond the main-channel links."""

    comm_bytes: int = 0
    control_links: np.ndarray | None = None  # (n, n) bool; None without a control channel
    control_bytes: int = 0
    latency_max: float = 0.0
    latency_mean: float = 0.0
    link_bytes: np.ndarray | None = None  # (n, n) int: bytes sent from agent i to agent j

    def to_json(self) -> dict[str, Any]:
        """The run log's ``comm`` object (links as flat indices, bytes as [i, j, n])."""
        control = self.control_links
        sent = self.link_bytes if self.link_bytes is not None else np.zeros((0, 0), np.int64)
        return {
            "bytes": int(self.comm_bytes),
            "sent": [[int(i), int(j), int(sent[i, j])] for i, j in np.argwhere(sent)],
            "control_links": None if control is None else np.flatnonzero(control).tolist(),
            "control_bytes": int(self.control_bytes),
            "latency": [float(self.latency_max), float(self.latency_mean)],
        }

    @classmethod
    def of(cls, record: Any, control_links: np.ndarray | None, sent: np.ndarray) -> CommSummary:
        """A step's summary from its record (bytes, latencies), the control channel's
        links (None: no control channel) and the bytes each pair sent."""
        return cls(
            record.comm_bytes, control_links, record.control_bytes, record.latency_max,
            record.latency_mean, sent,
        )  # fmt: skip

    @classmethod
    def from_json(cls, line: dict[str, Any] | None, n: int) -> CommSummary:
        """Read :meth:`to_json` back for ``n`` agents (empty for logs older than it)."""
        if line is None:
            return cls()
        control = line["control_links"]
        links = None if control is None else np.isin(np.arange(n * n), control).reshape(n, n)
        sent = np.zeros((n, n), dtype=np.int64)
        for i, j, count in line.get("sent", []):
            sent[i, j] = count
        latency_max, latency_mean = line["latency"]
        return cls(line["bytes"], links, line["control_bytes"], latency_max, latency_mean, sent)


@dataclass(frozen=True)
class MovableSnapshot:
    """A moving obstacle or a door at the end of a step (``world/views.py`` builds them).

    ``cells`` never changes for a given name during a run (the run log stores it once): an
    obstacle's footprint, or a door's leaf without the map's walls its ends lie in.
    """

    name: str
    kind: str  # "obstacle" or "door"
    cells: BoolGrid  # read-only; cells[0, 0] is the map cell ``at``
    at: tuple[int, int]  # (row, col) of the top-left cell
    on: bool  # on the map: an obstacle present, a door closed
    segment: tuple[tuple[float, float], tuple[float, float]] | None = None  # a door's ends


class GroundLayer(Protocol):
    """The ground classes a snapshot carries (``ground.grid.Ground``): the class of every
    cell (0: floor, i + 1: ``names[i]``), the names, their colours (RGB) and their
    default factors."""

    @property
    def grid(self) -> NDArray[np.uint8]: ...
    @property
    def names(self) -> tuple[str, ...]: ...
    @property
    def colours(self) -> tuple[tuple[int, int, int], ...]: ...
    @property
    def defaults(self) -> tuple[float, ...]: ...


@dataclass(frozen=True)
class Snapshot:
    """A whole run at the end of step ``step``; ``agents[0]`` is the base station.

    ``truth`` is a view of the world's occupancy grid, which may change during a run
    (``world_version`` tells which truth it is); ``movables``, ``rubble`` and
    ``gave_way`` tell the renderer which of its occupied cells are what.
    """

    step: int
    explored: float
    known_at_base: float
    alive: int
    truth: BoolGrid
    agents: tuple[AgentSnapshot, ...]
    links: np.ndarray  # (n, n) bool, same order as agents
    events: tuple[str, ...] = ()
    resolution: float | None = None
    dt: float | None = None  # seconds per step (scenario dt); None: the run is in steps only
    comm: CommSummary = field(default_factory=CommSummary)
    world_version: int = 0  # World.version: bumped by every change of the truth
    latest: bool = False  # robots' maps hold each cell's latest observation (belief: latest)
    terrain: NDArray[np.float32] | None = None  # true speed factors (static); None: no terrain
    ground: GroundLayer | None = None  # true ground classes (static, ground/); None: none
    prior: NDArray[np.uint8] | None = None  # the prior map robots were given (static); None
    hazards: NDArray[np.float32] | None = None  # hazard zones' failure probability (static)
    movables: tuple[MovableSnapshot, ...] = ()  # every obstacle and door, scenario order
    # cells only a failed robot knew when it fell silent (knowledge.robustness); None: none
    lost_knowledge: BoolGrid | None = None
    failures: tuple[tuple[int, str], ...] = ()  # (step, "B" or "C radio") of every failure
    rubble: BoolGrid | None = None  # static walls that were free on the map (None: none yet)
    gave_way: BoolGrid | None = None  # free cells that were the map's walls
    # what the explorable area was computed from (static): each robot's start, radius,
    # laser range and seeds (world.explorable); (): unknown (a log older than it)
    sights: tuple[RobotSight, ...] = ()
    # the rendezvous accounting at the end of the step (meeting_board.py); None: the run's
    # strategies plan no meetings
    meetings: MeetingBoard | None = None

    @property
    def base(self) -> AgentSnapshot:
        """The base station."""
        return self.agents[0]

    @property
    def robots(self) -> tuple[AgentSnapshot, ...]:
        """The robots, in scenario order."""
        return self.agents[1:]
