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
from dataclasses import dataclass, field, replace
from typing import Any, Literal

import numpy as np

from mresim_phys.broken_parts import (
    Factors,
    FailingPart,
    broken_in,
    fail_part,
    range_factor,
    repair_part,
    speed_factor,
)
from mresim_phys.knowledge.teammates import PAYLOAD, TeammateInfo, keep_payload
from mresim_phys.localization.feature import believed_pose
from mresim_phys.localization.odometry import Pose
from mresim_phys.memory import sparse_zeros
from mresim_phys.planning import Planner
from mresim_phys.strategies.base import Decision, Strategy
from mresim_phys.types import BeliefGrid, BoolGrid, FloatArray
from mresim_phys.world.sensing import Laser

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
    """A fresh all-unknown belief grid and an empty safe-space grid: zeros (UNKNOWN is 0),
    so the operating system maps a page of them only once a cell in it is written
    (:func:`~mresim_phys.memory.sparse_zeros`)."""
    return sparse_zeros(shape, np.uint8), sparse_zeros(shape, bool)


ESCAPED = 1.0  # cells from where a bump taught it nothing: it plans as usual again


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
    parent: str | None = None  # its parent in the team's hierarchy ('base', a robot, or none)
    children: tuple[str, ...] = ()  # the robots whose parent it is
    hops: int = 0  # robots from the base down to it along its parents (0: not under the base)
    features: dict[str, Any] = field(default_factory=dict)  # each feature's state (features.py)

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

    @property
    def believed_position(self) -> tuple[float, float]:
        """Where the agent believes it is: the base station knows its place (a robot with
        localisation overrides this with its believed pose)."""
        return self.position

    def own_record(self, step: int) -> TeammateInfo:
        """The record this agent sends about itself."""
        return TeammateInfo(self.name, self.position, None, self.state, self.role, step)


@dataclass
class Robot(Agent):
    """A mobile robot following its strategy's paths."""

    body: Body = field(kw_only=True)  # required: every robot has its hardware
    strategy: Strategy | None = None
    planner: Planner | None = None
    scans: int = 0  # scans taken so far (a battery drains per scan)
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
    escape_from: tuple[float, float] | None = None  # where a bump taught its map nothing

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

    @property
    def broken(self) -> frozenset[str]:
        """The parts that do not work now (``degraded`` while a degradation is in force;
        ``broken_parts.py``)."""
        return broken_in(self.features)

    def fail(self, part: FailingPart, factors: Factors = (1.0, 1.0)) -> None:
        """Lose ``part`` until a matching :meth:`repair` (``robot``: everything, the robot is
        ``failed``; ``degraded``: speed and sensor range scaled by ``factors``). Failures
        of one part add up: it works again once each has been repaired."""
        fail_part(self.features, part, factors)
        if part == "robot":
            self.status, self.path = "failed", self.path[:0]

    def repair(self, part: FailingPart, factors: Factors = (1.0, 1.0)) -> None:
        """Undo one failure of ``part`` (a reboot); the part works again once no failure of
        it is in force. A robot back from a whole failure replans at once."""
        left = repair_part(self.features, part, factors)
        if part == "robot" and left == 0 and self.status == "failed":
            self.status = "active"
            self.stop_for_replan()

    @property
    def speed_factor(self) -> float:
        """The product of the speed factors of the degradations in force (1: none)."""
        return speed_factor(self.features)

    @property
    def range_factor(self) -> float:
        """The product of the sensor range factors of the degradations in force (1: none)."""
        return range_factor(self.features)

    @property
    def laser(self) -> Laser:
        """Its laser as it works now (range scaled while degraded)."""
        factor = self.range_factor
        laser = self.body.laser
        return laser if factor == 1.0 else replace(laser, range=laser.range * factor)

    @property
    def state(self) -> str:
        """``failed`` beats ``error`` beats ``done`` beats ``active``."""
        if self.status in ("failed", "error"):
            return self.status
        return "done" if self.done else "active"

    def own_record(self, step: int) -> TeammateInfo:
        """Position, goal, state, role, payload and failed parts, stamped with ``step``."""
        x, y, _ = self.believed
        return TeammateInfo(
            self.name,
            (x, y),
            self.goal,
            self.state,
            self.role,
            step,
            payload=PAYLOAD.state_of(self.features),
            broken=tuple(sorted(self.broken)),
        )

    @property
    def believed(self) -> Pose:
        """The pose the robot believes it has: its map's, its plans' and its record's
        (``localization/feature.py``; without localisation, its true pose)."""
        return believed_pose(self.features, self.position, self.heading)

    @property
    def believed_position(self) -> tuple[float, float]:
        """The position the robot believes it has."""
        x, y, _ = believed_pose(self.features, self.position, self.heading)
        return (x, y)

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
        keep_payload(self.features, decision.payload)

    @property
    def speed(self) -> float:
        """Cells moved at most per step (scaled while degraded)."""
        factor = self.speed_factor
        return self.body.speed if factor == 1.0 else self.body.speed * factor

    @property
    def radius(self) -> float:
        """Body radius in cells."""
        return self.body.radius

    def advance_to(self, point: tuple[float, float]) -> None:
        """Move to ``point`` (already checked against walls), turning to face the motion."""
        dx, dy = point[0] - self.position[0], point[1] - self.position[1]
        self.distance += math.hypot(dx, dy)
        self.heading = math.atan2(dy, dx)
        self.position = point
        away = self.escape_from
        if away is not None and math.hypot(point[0] - away[0], point[1] - away[1]) > ESCAPED:
            self.escape_from = None
