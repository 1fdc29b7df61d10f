"""Agents: what each robot and the base station is and knows.

A robot's knowledge is its own belief grid (and safe-space grid) plus the last
state it heard from each teammate; nothing here reads the ground truth. The
simulation (``sim.py``) moves robots and feeds them scans; communication
(``comms/``) merges knowledge between linked agents.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from mresim_phys.planning import Planner
from mresim_phys.scenario.schema import RobotSpec
from mresim_phys.strategies.base import Decision, Strategy
from mresim_phys.types import UNKNOWN, BeliefGrid, BoolGrid, FloatArray

RobotState = Literal["active", "error", "done", "failed"]
BASE_NAME = "base"


@dataclass(frozen=True)
class TeammateInfo:
    """What one agent last heard about another: where it was, where it was heading, when.

    ``step`` is when the record was true (its sender's step); ``learned`` the step at
    which the holder received it (-1 for an agent's own record, not yet sent).
    """

    name: str
    position: tuple[float, float]
    goal: tuple[float, float] | None
    state: str
    role: str
    step: int
    learned: int = -1


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

    @property
    def alive(self) -> bool:
        """Whether this agent still senses, moves and communicates."""
        return True

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

    spec: RobotSpec | None = None
    strategy: Strategy | None = None
    planner: Planner | None = None
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

    @property
    def alive(self) -> bool:
        """Failed robots neither move, sense nor communicate."""
        return self.status != "failed"

    @property
    def state(self) -> str:
        """``failed`` beats ``error`` beats ``done`` beats ``active``."""
        if self.status in ("failed", "error"):
            return self.status
        return "done" if self.done else "active"

    def own_record(self, step: int) -> TeammateInfo:
        """Position, goal, state and role, stamped with ``step``."""
        return TeammateInfo(self.name, self.position, self.goal, self.state, self.role, step)

    def adopt(self, decision: Decision, step: int) -> None:
        """Take a strategy decision as the path to follow from now on."""
        self.path = decision.path
        self.goal = decision.goal
        self.done = decision.done
        self.last_plan_step = step
        self.reached_goal = False
        self.decision = decision

    @property
    def speed(self) -> float:
        """Cells moved at most per step."""
        assert self.spec is not None
        return self.spec.speed

    @property
    def radius(self) -> float:
        """Body radius in cells."""
        assert self.spec is not None
        return self.spec.radius

    def advance_to(self, point: tuple[float, float]) -> None:
        """Move to ``point`` (already checked against walls), turning to face the motion."""
        dx, dy = point[0] - self.position[0], point[1] - self.position[1]
        self.distance += math.hypot(dx, dy)
        self.heading = math.atan2(dy, dx)
        self.position = point
