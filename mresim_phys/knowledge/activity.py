"""Run health's per-robot feature (phase 7, measure): what a robot did in the step, and why
its state changed.

:data:`HEALTH` (key ``health``, ``features.py``) is the run-health watch's view of one
robot at the end of a step (``knowledge/health.py``, ``HealthWatch.view``): its
*activity* (``working``, ``fruitless``, ``waiting``, ``idle``, ``stuck``; ``""`` when not
assessed) and the *reason* of a change of its reported state in the step (None: no
change). It keeps no state in the robot: the snapshot is given the watch's view when it is
built (``agent_views.agent_snapshot``), and records it while either part says something.

The run log stores only the reason, under ``health`` in the robot's line, at a step where
its state changed (``state_reason`` in logs of version 6 or older): the replay recomputes
the activity with its own watch (``output.runlog.Replay``, :func:`with_activity`). Frames
show the activity as a glyph and a tag after the label (``render.draw``), the viewer's
hover row as ``health``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from mresim_phys.features import HasFeatures, PlainFeature


@dataclass(frozen=True)
class Health:
    """A robot's activity in the step and the reason its state changed in it."""

    activity: str = ""
    reason: str | None = None

    def __bool__(self) -> bool:
        """Whether it says anything (an assessed activity or a change of state)."""
        return bool(self.activity) or self.reason is not None


class HealthFeature(PlainFeature[Health]):
    """The run-health watch's view of a robot (module docstring)."""

    key = "health"
    omit_empty = True

    def encode(self, value: Health) -> Any:
        """The reason only (None: nothing to log; the activity is recomputed on replay)."""
        return value.reason

    def decode(self, raw: Any) -> Health:
        """A logged reason, with the activity still to recompute."""
        return Health("", str(raw))

    def hover(self, value: Health) -> Any:
        """The activity ('' when not assessed)."""
        return value.activity


HEALTH = HealthFeature()
NO_HEALTH = Health()


def health_of(holder: HasFeatures) -> Health:
    """A robot's activity and reason of a state change (nothing recorded: neither)."""
    return HEALTH.of(holder) or NO_HEALTH


def with_health(states: Mapping[str, Any], activity: str, reason: str | None) -> dict[str, Any]:
    """An agent's feature ``states`` with the watch's view of it now."""
    return {**states, HEALTH.key: Health(activity, reason)}


def with_activity(robot: HasFeatures, activity: str) -> dict[str, Any]:
    """A replayed robot's recorded feature values with its recomputed ``activity`` (no
    entry when it has neither an activity nor a logged reason)."""
    health = Health(activity, health_of(robot).reason)
    rest = {k: v for k, v in robot.features.items() if k != HEALTH.key}
    return {**rest, HEALTH.key: health} if health else rest
