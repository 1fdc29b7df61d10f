"""Fault models (phase 0, events; and after the communication phase): faults acting on a run.

:class:`Faults` holds the scenario's ``faults:`` block built for one run: the
robots' failure clocks (``clocks.py``), the hazard zones as cells with each robot's
exposure budget, the batteries and the out-of-contact rule. In the events phase,
after the scheduled events and the world's elements, :meth:`Faults.apply` fails (and
repairs) robots whose clocks are due, counts a step of exposure for every working
robot standing in a hazard zone (and fails it when its budget is spent), and fails
robots that have been out of contact for too long. After the communication phase,
:meth:`Faults.drain` takes from each battery what the step cost (distance moved,
scans, messages sent); a robot whose battery is empty fails there and then (the battery,
a per-robot feature, is ``faults/battery.py``).

Nobody is told: a failure changes only the robot (``Robot.fail``); teammates notice
its silence (``knowledge/teammates.py``: presumed lost).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from mresim_phys.agents import Robot
from mresim_phys.errors import ScenarioError
from mresim_phys.faults.battery import battery_of, give_battery, use
from mresim_phys.faults.clocks import FailureClock, exposure_budget
from mresim_phys.faults.spec import FaultsSpec, HazardSpec, PartSpec, RandomFaultSpec, chosen
from mresim_phys.localization.faults import jump_belief
from mresim_phys.rng import Streams
from mresim_phys.types import BoolGrid
from mresim_phys.world.footprints import region_cells

HAZARD_STREAM, FAULT_STREAM = "hazard", "fault"


@dataclass
class Hazard:
    """One hazard zone on the map and each robot's exposure so far and budget."""

    spec: HazardSpec
    cells: BoolGrid
    budget: dict[str, int]  # steps inside each robot survives (drawn once)
    inside: dict[str, int] = field(default_factory=dict)  # steps spent inside so far

    def strikes(self, robot: Robot) -> bool:
        """Count a step of ``robot`` inside (if it is); True on the step that fails it."""
        if robot.name not in self.budget or not robot.alive:
            return False
        x, y = robot.position
        rows, cols = self.cells.shape
        row, col = min(max(int(y), 0), rows - 1), min(max(int(x), 0), cols - 1)
        if not self.cells[row, col]:
            return False
        self.inside[robot.name] = self.inside.get(robot.name, 0) + 1
        if self.inside[robot.name] == self.budget[robot.name]:
            del self.budget[robot.name]  # one failure per zone and robot
            return True
        return False


class Faults:
    """The ``faults:`` block of one run, acting on its robots."""

    def __init__(
        self,
        spec: FaultsSpec,
        robots: Sequence[Robot],
        zones: Sequence[BoolGrid],
        streams: Streams,
    ) -> None:
        self.robots = list(robots)
        self.clocks = [
            FailureClock(r.name, law, streams.of_robot(f"{FAULT_STREAM}/{k}", r.name))
            for k, law in enumerate(spec.random)
            for r in self.robots
            if chosen(law.robots, r.name)
        ]
        self.hazards = [
            Hazard(h, cells, budgets(h, self.robots, streams, k))
            for k, (h, cells) in enumerate(zip(spec.hazards, zones, strict=True))
        ]
        if spec.battery is not None:
            for robot in self.robots:
                if chosen(spec.battery.robots, robot.name):
                    give_battery(robot, spec.battery)
        self.contact_limit = spec.fail_if_out_of_contact_for
        self.last_contact = dict.fromkeys((r.name for r in self.robots), 0)
        self.by_name = {r.name: r for r in self.robots}

    def apply(self, step: int) -> list[str]:
        """Events phase: due clocks, hazard exposure and the out-of-contact rule; the lines
        logged."""
        lines: list[str] = []
        for clock in self.clocks:
            what = clock.due(step)
            line = act(self.by_name[clock.robot], what, clock.spec) if what else None
            if line is not None:
                lines.append(line)
        for k, hazard in enumerate(self.hazards):
            for robot in self.robots:
                if hazard.strikes(robot):
                    lines.append(f"{strike(robot, hazard.spec)} (hazard {k})")
        if self.contact_limit is not None:
            lines += self.out_of_contact(step, self.contact_limit)
        return lines

    def out_of_contact(self, step: int, limit: int) -> list[str]:
        """Fail every working robot without a link for more than ``limit`` steps."""
        lines = []
        for robot in self.robots:
            if robot.alive and step - self.last_contact[robot.name] > limit:
                robot.fail("robot")
                lines.append(f"fail {robot.name} (out of contact for {limit} steps)")
        return lines

    def drain(self, sent: Sequence[np.ndarray], step: int) -> list[str]:
        """After the communication phase: note links, take from each battery what the step
        cost (``sent``: per channel, ``[i, j]`` bytes agent i sent agent j; robot i is
        agent i); the lines logged (robots whose battery ran out, which fail)."""
        for robot in self.robots:
            if robot.links:
                self.last_contact[robot.name] = step
        lines = []
        for robot in self.robots:
            battery = battery_of(robot)
            if battery is None or battery.charge <= 0:
                continue
            messages = sum(int(np.count_nonzero(s[robot.index])) for s in sent)
            if use(battery, robot, messages) and robot.alive:
                robot.fail("robot")
                lines.append(f"fail {robot.name} (battery empty)")
        return lines


def budgets(spec: HazardSpec, robots: Sequence[Robot], streams: Streams, k: int) -> dict[str, int]:
    """Each chosen robot's exposure budget in zone ``k``: one draw from its own stream."""
    return {
        r.name: exposure_budget(spec.probability, streams.of_robot(f"{HAZARD_STREAM}/{k}", r.name))
        for r in robots
        if chosen(spec.robots, r.name)
    }


def act(robot: Robot, what: str, spec: RandomFaultSpec) -> str | None:
    """Apply a clock's ``fail`` or ``repair`` to ``robot``; the line logged (a jump is
    over at once: its repair is nothing)."""
    if what == "fail":
        return f"{strike(robot, spec)} (random)"
    if spec.mode == "jump":
        return None
    robot.repair(spec.part, spec.factors)
    return f"recover {robot.name}{suffix(spec.part)}"


def strike(robot: Robot, spec: PartSpec) -> str:
    """Fail ``spec``'s part of ``robot`` (a localisation jump: throw its belief off); the
    line logged, without its cause."""
    if spec.mode == "jump" and spec.distance is not None:
        jump_belief(robot.features, robot.name, spec.distance)
        return f"jump {robot.name} localization {spec.distance:g} cells"
    robot.fail(spec.part, spec.factors)
    return f"fail {robot.name}{suffix(spec.part)}"


def suffix(part: str) -> str:
    """`` drive`` for a part, nothing for the whole robot."""
    return "" if part == "robot" else f" {part}"


def build_faults(
    spec: FaultsSpec | None, robots: Sequence[Robot], shape: tuple[int, int], streams: Streams
) -> Faults | None:
    """The run's faults (None without a ``faults:`` block); a ScenarioError naming the field
    if a hazard zone covers no cell of the map."""
    if spec is None:
        return None
    zones = []
    for k, hazard in enumerate(spec.hazards):
        try:
            zones.append(region_cells(hazard.region, shape))
        except ValueError as exc:
            raise ScenarioError(
                f"faults.hazards[{k}].region: {exc} ({shape[1]}x{shape[0]} cells); give a"
                " zone inside the map."
            ) from None
    return Faults(spec, robots, zones, streams)


def hazard_grid(faults: Faults | None, shape: tuple[int, int]) -> NDArray[np.float32] | None:
    """Per cell, the highest failure probability per step of the zones over it (the
    ``hazards`` video layer); None without hazard zones."""
    if faults is None or not faults.hazards:
        return None
    grid = np.zeros(shape, dtype=np.float32)
    for hazard in faults.hazards:
        np.maximum(grid, np.float32(hazard.spec.probability) * hazard.cells, out=grid)
    return grid
