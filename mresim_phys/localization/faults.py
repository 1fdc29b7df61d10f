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

from collections.abc import Mapping
from typing import Any

from mresim_phys.broken_parts import broken_in
from mresim_phys.localization.feature import LOCALIZATION


def jump_belief(states: Mapping[str, Any], name: str, distance: float) -> None:
    """Throw the believed pose of the robot ``name`` with feature ``states`` (its
    ``Robot.features``) ``distance`` cells off (``mode: jump``)."""
    loc = LOCALIZATION.state_of(states)
    if loc is None:
        raise ValueError(f"robot {name!r} has no localisation to jump")
    loc.jump(distance)


def frozen(states: Mapping[str, Any]) -> bool:
    """Whether the localisation of a robot with feature ``states`` is frozen (``mode:
    frozen`` in force)."""
    return "localization" in broken_in(states)
