"""World (phase 0, events): moving obstacles, people-like bodies that move through the building.

An obstacle (``obstacles:`` in a scenario) has a shape (``world/shapes.py``), a motion
and a life span (``appear``, ``remove``). Its body is the shape's footprint of whole
cells (the truth grid is cells), standing where its continuous centre is: every
change of cell moves the footprint in the world (``World.move_movable``), so rays,
line of sight, path loss and robots' swept-circle motion checks meet it exactly
where the truth grid has it. Motions:

* ``waypoints``: along the listed points at ``speed`` cells per step, then
  ``loop`` (back to the first), ``back_and_forth`` or ``once`` (it stays at the end);
* ``random_walk``: from its start at ``speed``, turning by a uniform angle of at most
  ``turn_rate`` degrees each step, drawn from the obstacle's own named stream;
* ``still``: it stands at one point from ``appear`` until ``remove``.

The wait rule: an obstacle never overlaps a wall, another obstacle or a robot's
body. When the footprint its next position needs would, it waits where it is that
step (a random walker also draws a new heading); it appears only once its place is
clear. Obstacles move in the events phase, before robots decide and move, and
robots' motion checks see them, so a robot never drives into one either.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import ClassVar, Protocol

import numpy as np

from mresim_phys.types import BoolGrid
from mresim_phys.world.element_params import ObstacleParams, RandomWalkMotion, WaypointsMotion
from mresim_phys.world.footprints import body_cells

Point = tuple[float, float]


class ObstacleWorld(Protocol):
    """What an obstacle needs from the run (a part of the events' context)."""

    @property
    def step(self) -> int:
        """The step now starting."""
        ...

    def place_obstacle(
        self,
        name: str,
        footprint: BoolGrid,
        at: tuple[int, int],
        blocks_radio: bool = True,
        over_walls: bool = False,
    ) -> bool:
        """Put or move ``name``'s footprint with its top-left cell at ``at``; False (and
        nothing changes) if it would leave the map or overlap another obstacle, a robot
        or (unless ``over_walls``: a door's ends lie in the walls) a wall."""
        ...

    def remove_obstacle(self, name: str) -> None:
        """Take ``name`` off the map."""
        ...

    def log(self, line: str) -> None:
        """Note what happened this step."""
        ...


def advance(points: Sequence[Point], position: Point, target: int, distance: float,
            mode: str, direction: int) -> tuple[Point, int, int]:  # fmt: skip
    """Move ``distance`` from ``position`` along the waypoints towards ``points[target]``
    and on; returns the new position, the next target index and direction (+1 / -1)."""
    x, y = position
    while distance > 1e-12 and len(points) > 1:
        tx, ty = points[target]
        gap = math.hypot(tx - x, ty - y)
        if gap > distance:
            share = distance / gap
            return (x + share * (tx - x), y + share * (ty - y)), target, direction
        x, y, distance = tx, ty, distance - gap
        target, direction = next_target(len(points), target, mode, direction)
        if target < 0:
            return (x, y), -1, direction
    return (x, y), target, direction


def next_target(count: int, target: int, mode: str, direction: int) -> tuple[int, int]:
    """The waypoint after ``target`` (-1 once a ``once`` path has ended) and the direction."""
    following = target + direction
    if 0 <= following < count:
        return following, direction
    if mode == "loop":
        return 0, 1
    if mode == "back_and_forth":
        return target - direction, -direction
    return -1, direction


class MovingObstacle:
    """One obstacle's state over a run: where it is, where it is going, whether it is on
    the map. :meth:`apply` runs once per step in the events phase."""

    kind: ClassVar[str] = "obstacle"

    def __init__(self, params: ObstacleParams, rng: np.random.Generator) -> None:
        self.params = params
        self.rng = rng
        self.footprint, self.centre_cell = body_cells(params.shape)
        self.footprint.flags.writeable = False  # shared with the world's Movable
        self.position: Point = params.points()[0]
        self.on_map = False
        self.target, self.direction = (1 if len(params.points()) > 1 else -1), 1
        self.heading = 0.0
        if isinstance(params.motion, RandomWalkMotion):
            self.heading = float(rng.uniform(0.0, 2.0 * math.pi))

    def top_left(self, position: Point) -> tuple[int, int]:
        """The footprint's top-left cell when its centre stands at ``position``."""
        return (math.floor(position[1]) - self.centre_cell[0],
                math.floor(position[0]) - self.centre_cell[1])  # fmt: skip

    def apply(self, world: ObstacleWorld) -> None:
        """Enter, move or leave the map at this step (see the module docstring)."""
        p, step = self.params, world.step
        if p.remove is not None and step >= p.remove:
            if self.on_map:
                world.remove_obstacle(p.name)
                world.log(f"obstacle {p.name} leaves")
                self.on_map = False
            return
        if step < p.appear:
            return
        if not self.on_map:
            self.on_map = self._place(world, self.position)
            if self.on_map:
                world.log(f"obstacle {p.name} appears")
            return
        proposal = self._proposal()
        if proposal is None:
            return
        position, target, direction = proposal
        if self.top_left(position) == self.top_left(self.position) or self._place(world, position):
            self.position, self.target, self.direction = position, target, direction
        elif isinstance(p.motion, RandomWalkMotion):  # blocked: try another way next step
            self.heading = float(self.rng.uniform(0.0, 2.0 * math.pi))

    def _place(self, world: ObstacleWorld, position: Point) -> bool:
        at = self.top_left(position)
        return world.place_obstacle(self.params.name, self.footprint, at, self.params.blocks_radio)

    def _proposal(self) -> tuple[Point, int, int] | None:
        """Where the motion would take it this step (None: it does not move)."""
        motion = self.params.motion
        if isinstance(motion, WaypointsMotion):
            if self.target < 0:
                return None
            return advance(motion.waypoints, self.position, self.target, motion.speed,
                           motion.mode, self.direction)  # fmt: skip
        if isinstance(motion, RandomWalkMotion):
            turn = math.radians(motion.turn_rate)
            self.heading += float(self.rng.uniform(-turn, turn))
            x, y = self.position
            step = (x + motion.speed * math.cos(self.heading),
                    y + motion.speed * math.sin(self.heading))  # fmt: skip
            return step, self.target, self.direction
        return None
