"""The battery (phase 9, after the communication phase): a per-robot feature, whole.

A scenario's ``faults.battery`` gives the listed robots a battery that drains as the robot
moves, scans and sends (:func:`use`, called by ``Faults.drain``); empty, the robot fails.
Everything else about it is here, as a :class:`~mresim_phys.features.RobotFeature`:

* the state, :class:`Battery` in ``Robot.features["battery"]``;
* the value a strategy sees and a snapshot records: the level left, a fraction of the
  capacity (``BATTERY.of(view)``);
* the run log stores the level under ``battery`` in each agent's line (a float);
* frames label the robot with its level (``B 73%``), the viewer's hover row shows it;
* the optional metric column ``robot_battery`` (``battery_<robot>``: the level, '' for a
  robot without one).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from mresim_phys.agents import Robot
from mresim_phys.columns import column
from mresim_phys.faults.spec import BatterySpec
from mresim_phys.features import RobotFeature
from mresim_phys.metrics import StepRecord


@dataclass
class Battery:
    """A robot's battery: its charge and what the robot had done when it was last drained."""

    spec: BatterySpec
    charge: float
    distance: float = 0.0
    scans: int = 0


class BatteryFeature(RobotFeature[Battery, float]):
    """The battery level left, a fraction of the capacity."""

    key = "battery"

    def value(self, state: Battery) -> float:
        """The level left: charge over capacity."""
        return state.charge / state.spec.capacity

    def encode(self, value: float) -> Any:
        """A float, at full precision."""
        return float(value)

    def decode(self, raw: Any) -> float:
        """The logged float."""
        return float(raw)

    def label(self, value: float) -> str:
        """`` 73%``."""
        return f" {value:.0%}"

    def hover(self, value: float) -> Any:
        """The level, to 4 decimals."""
        return round(value, 4)


BATTERY = BatteryFeature()


def give_battery(robot: Robot, spec: BatterySpec) -> None:
    """A full battery of ``spec`` for ``robot``."""
    robot.features[BATTERY.key] = Battery(spec, spec.capacity)


def battery_of(robot: Robot) -> Battery | None:
    """``robot``'s battery (None: it has none)."""
    battery: Battery | None = robot.features.get(BATTERY.key)
    return battery


def use(battery: Battery, robot: Robot, messages: int) -> bool:
    """Take what ``robot`` did since the last drain from ``battery``; True if it is empty."""
    spec = battery.spec
    cost = spec.per_cell * (robot.distance - battery.distance)
    cost += spec.per_scan * (robot.scans - battery.scans) + spec.per_message * messages
    battery.distance, battery.scans = robot.distance, robot.scans
    battery.charge = max(battery.charge - cost, 0.0)
    return battery.charge <= 0


@column("robot_battery", per_robot=True, prefix="battery", optional=True)
def robot_battery(r: StepRecord) -> Sequence[float | None]:
    """Each robot's battery level (a fraction of its capacity; '' without a battery)."""
    return [BATTERY.of(robot) for robot in r.robots]
