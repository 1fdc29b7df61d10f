"""Localisation faults (phase 0, events): a robot whose localisation fails.

The part ``localization`` of a ``fail`` event or of a fault model of the ``faults:`` block
(``world/parts.py``) fails in one of two modes:

* ``frozen``: the part is broken (``Robot.broken``, the ``parts`` feature) until repaired;
  meanwhile the believed pose no longer follows the odometry (the robot drives from a
  belief that stands still, folds every scan there and takes no correction), so its map
  smears while its teammates' stay sharp; a repair lets it follow again from where it
  stood;
* ``jump``: the believed pose is thrown ``distance`` cells off at once, in a direction
  drawn from the robot's ``jump`` stream, its covariance unchanged (it does not know):
  the kidnapped robot. Nothing stays broken.

A robot a localisation fault may strike is given localisation by ``build.py`` even
without a ``localization:`` block (no drift, no corrections).
"""

from __future__ import annotations

from mresim_phys.agents import Robot
from mresim_phys.localization.feature import LOCALIZATION


def jump_belief(robot: Robot, distance: float) -> None:
    """Throw ``robot``'s believed pose ``distance`` cells off (``mode: jump``)."""
    loc = LOCALIZATION.state_of(robot.features)
    if loc is None:
        raise ValueError(f"robot {robot.name!r} has no localisation to jump")
    loc.jump(distance)


def frozen(robot: Robot) -> bool:
    """Whether ``robot``'s localisation is frozen (``mode: frozen`` in force)."""
    return "localization" in robot.broken
