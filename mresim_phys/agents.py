"""Agents (the run's state): what each robot and the base station is and knows.

A robot's knowledge is its own belief grid (and safe-space grid) plus the last
record it heard from each teammate (:mod:`mresim_phys.knowledge.teammates`);
nothing here reads the ground truth. Its body (speed, radius, laser) is a plain
:class:`Body` made by the composition root. The simulation (``sim.py``) moves
robots and feeds them scans; communication (``comms/``) merges knowledge between
linked agents.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from mresim_phys.knowledge.teammates import Payload, TeammateInfo
from mresim_phys.planning import Planner
from mresim_phys.strategies.base import Decision, Strategy
from mresim_phys.types import UNKNOWN, BeliefGrid, BoolGrid, FloatArray
from mresim_phys.world.sensing import Laser
from mresim_phys.world.terrain import TerrainGrid

RobotState = Literal["active", "error", "done", "failed"]
Part = Literal["drive", "sensor", "radio"]


@dataclass(frozen=True)
class Body:
    """A robot's hardware: how fast it moves, how big it is, what its laser sees."""

    speed: float  # cells per step at most
    radius: float  # cells
    wall_margin: float  # extra clearance its planner keeps from known walls
    laser: Laser


def empty_belief(shape: tuple[int, int]) -> tuple[BeliefGrid, BoolGrid]:
    """A fresh all-unknown belief grid and an empty safe-space grid."""
    return np.full(shape, UNKNOWN, dtype=np.uint8), np.zeros(shape, dtype=bool)


@dataclass
class Agent:
    """Anything that communicates: a robot or the base station."""

    name: str
    index: int
    position: tuple[float, float]
    comm_range: float
    belief: BeliefGrid
    safe: BoolGrid
    role: str
    teammates: dict[str, TeammateInfo] = field(default_factory=dict)
    last_base_contact: int = -1
    links: tuple[str, ...] = ()  # agents linked on the main channel at the last exchange
    # step of each cell's latest observation (-1: never), kept when beliefs are 'latest'
    observed: NDArray[np.int32] | None = None

    @property
    def alive(self) -> bool:
        """Whether this agent still senses, moves and communicates."""
        return True

    @property
    def speaking(self) -> bool:
        """Whether its radio works (it can send and receive)."""
        return self.alive

    @property
    def state(self) -> str:
        """The state reported in metrics and to teammates."""
        return "active"

    def own_record(self, step: int) -> TeammateInfo:
        """The record this agent sends about itself."""
        return TeammateInfo(self.name, self.position, None, self.state, self.role, step)


@dataclass
class Robot(Agent):
    """A mobile robot following its strategy's paths."""

    body: Body | None = None
    strategy: Strategy | None = None
    planner: Planner | None = None
    broken: frozenset[Part] = frozenset()  # parts that failed for good
    payload: Payload | None = None  # what its strategy sends with its record
    heading: float = 0.0
    path: FloatArray = field(default_factory=lambda: np.zeros((0, 2)))
    goal: tuple[float, float] | None = None
    distance: float = 0.0
    status: RobotState = "active"
    done: bool = False
    last_plan_step: int = -(10**9)
    reached_goal: bool = False
    rng: np.random.Generator = field(default_factory=lambda: np.random.default_rng(0))
    decision: Decision | None = None
    terrain: TerrainGrid | None = None  # known terrain factors (knowledge/terrain.py); None: none
    prior: BeliefGrid | None = None  # the map it knew before the mission (knowledge/prior.py)

    @property
    def alive(self) -> bool:
        """Failed robots neither move, sense nor communicate."""
        return self.status != "failed"

    @property
    def speaking(self) -> bool:
        """Alive with a working radio."""
        return self.alive and "radio" not in self.broken

    @property
    def can_move(self) -> bool:
        """Alive with a working drive."""
        return self.alive and "drive" not in self.broken

    @property
    def can_sense(self) -> bool:
        """Alive with a working laser."""
        return self.alive and "sensor" not in self.broken

    def fail(self, part: Literal["robot"] | Part) -> None:
        """Lose ``part`` for good (``robot``: everything, the robot is ``failed``)."""
        if part == "robot":
            self.status, self.path = "failed", self.path[:0]
        else:
            self.broken = self.broken | {part}

    @property
    def state(self) -> str:
        """``failed`` beats ``error`` beats ``done`` beats ``active``."""
        if self.status in ("failed", "error"):
            return self.status
        return "done" if self.done else "active"

    def own_record(self, step: int) -> TeammateInfo:
        """Position, goal, state, role and payload, stamped with ``step``."""
        return TeammateInfo(
            self.name, self.position, self.goal, self.state, self.role, step, payload=self.payload
        )

    def stop_for_replan(self) -> None:
        """Drop the path: something the robot now senses blocks it. It stands until its
        replan, which is due at once (the next decide phase)."""
        self.path = np.zeros((0, 2))
        self.last_plan_step = -(10**9)

    def adopt(self, decision: Decision, step: int) -> None:
        """Take a decision (its strategy's or a controller's) as the path to follow from now on."""
        self.path = decision.path
        self.goal = decision.goal
        self.done = decision.done
        self.last_plan_step = step
        self.reached_goal = False
        self.decision = decision
        if decision.role is not None:
            self.role = decision.role
        self.payload = decision.payload

    @property
    def speed(self) -> float:
        """Cells moved at most per step."""
        assert self.body is not None
        return self.body.speed

    @property
    def radius(self) -> float:
        """Body radius in cells."""
        assert self.body is not None
        return self.body.radius

    def advance_to(self, point: tuple[float, float]) -> None:
        """Move to ``point`` (already checked against walls), turning to face the motion."""
        dx, dy = point[0] - self.position[0], point[1] - self.position[1]
        self.distance += math.hypot(dx, dy)
        self.heading = math.atan2(dy, dx)
        self.position = point
