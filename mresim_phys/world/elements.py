"""World (phase 0, events): the parts of the world that act every step, built for a run.

A *world element* is a moving obstacle (``world/obstacles.py``), a door
(``world/doors.py``) or the random debris (``world/debris.py``) of a scenario. The
events phase moves every element after the step's scheduled events (so a
``close`` event reaches its door the same step), in scenario order: obstacles,
doors, then debris. Each element that draws random numbers has its own named
stream of the scenario seed (``obstacle/<name>``, ``debris``), so adding an
obstacle never changes another's walk, nor the robots' draws.

:func:`build_elements` makes them from the validated scenario and checks what only
the map can tell: every point on the map, no obstacle starting on a wall or a
robot's start, door names that events use, debris regions (mask images) readable.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Protocol

from mresim_phys.errors import ScenarioError
from mresim_phys.rng import Streams
from mresim_phys.types import FloatArray
from mresim_phys.world.debris import DebrisWorld, RandomDebris
from mresim_phys.world.doors import Door
from mresim_phys.world.element_params import DoorParams, ObstacleParams, RandomDebrisParams
from mresim_phys.world.obstacles import MovingObstacle, ObstacleWorld
from mresim_phys.world.space import World


class ElementWorld(ObstacleWorld, DebrisWorld, Protocol):
    """What world elements may do to a run: the events' context implements it."""


class WorldElement(Protocol):
    """A part of the world that acts once per step in the events phase."""

    def apply(self, world: ElementWorld) -> None:
        """Act at ``world.step`` through the events' context."""
        ...


def check_points(field: str, points: Sequence[tuple[float, float]], shape: tuple[int, int]) -> None:
    """Every point must lie on the map."""
    rows, cols = shape
    for x, y in points:
        if not (0 <= x < cols and 0 <= y < rows):
            raise ScenarioError(
                f"{field}: the point [{x:g}, {y:g}] is not on the {cols}x{rows} map; give"
                f" 0 <= x < {cols} and 0 <= y < {rows}."
            )


def check_names(obstacles: Sequence[ObstacleParams], doors: Sequence[DoorParams]) -> None:
    """Obstacle and door names must be unique (events and logs name them)."""
    seen: set[str] = set()
    for field, name in [("obstacles", o.name) for o in obstacles] + [
        ("doors", d.name) for d in doors
    ]:
        if name in seen:
            raise ScenarioError(
                f"{field}: the name {name!r} is used twice; give each its own name."
            )
        seen.add(name)


def build_elements(
    obstacles: Sequence[ObstacleParams],
    doors: Sequence[DoorParams],
    debris: RandomDebrisParams | None,
    world: World,
    streams: Streams,
    robots: FloatArray,
    base_dir: Path | None = None,
) -> list[MovingObstacle | Door | RandomDebris]:
    """The run's world elements, in the order they act (see the module docstring);
    ``robots`` are the robots' bodies at the start (rows of x, y, radius)."""
    check_names(obstacles, doors)
    elements: list[MovingObstacle | Door | RandomDebris] = []
    for i, params in enumerate(obstacles):
        check_points(f"obstacles[{i}] ({params.name})", params.points(), world.shape)
        obstacle = MovingObstacle(params, streams.get(f"obstacle/{params.name}"))
        at = obstacle.top_left(obstacle.position)
        if params.appear == 0 and not world.fits(obstacle.footprint, at, robots):
            raise ScenarioError(
                f"obstacles[{i}] ({params.name}): at {list(obstacle.position)} its shape would"
                " overlap a wall, another obstacle, a robot or the map's edge; move it, make it"
                " smaller or let it appear later."
            )
        elements.append(obstacle)
    for i, door in enumerate(doors):
        check_points(f"doors[{i}] ({door.name})", door.points(), world.shape)
        elements.append(Door(door))
    if debris is not None:
        try:
            elements.append(RandomDebris(debris, streams.get("debris"), world.shape, base_dir))
        except ValueError as exc:
            raise ScenarioError(f"random_debris.region: {exc}") from None
    return elements
