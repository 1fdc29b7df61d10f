"""Run-health outputs (output edge): summary.json's ``health``, its warnings, its replay.

:func:`run_health` is the ``health`` object of a live run's summary.json (the watch of
``knowledge/health.py`` at the run's last step, with a last frontier check of every
robot's map); :func:`print_warnings` writes its warnings to stderr at the end of a command
line run; :func:`replayed_health` rebuilds the same object from a run log alone and
:func:`compare_health` tells ``mresim replay --metrics`` whether a recomputed one equals
the live one.
Format and meaning: docs/run-health.md.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any, TextIO

from mresim_phys.health_phase import robot_steps
from mresim_phys.output.runlog import Replay, RunLog

if TYPE_CHECKING:
    from mresim_phys.sim import Simulation

HEALTH = "health"


def run_health(sim: Simulation) -> dict[str, Any]:
    """summary.json's ``health`` object of ``sim`` at its last step."""
    steps = robot_steps(sim.robots, sim.health, sim.t, sim.events_now)
    return {HEALTH: sim.health.report(steps).summary()}


def warnings_of(summary: dict[str, Any]) -> list[str]:
    """The run-health warnings of a summary (none if it has no health record)."""
    health = summary.get(HEALTH)
    return list(health.get("warnings", [])) if isinstance(health, dict) else []


def print_warnings(summary: dict[str, Any], out: TextIO | None = None) -> None:
    """Write each run-health warning of ``summary`` as one line (to stderr by default)."""
    stream = sys.stderr if out is None else out
    for text in warnings_of(summary):
        print(f"mresim: warning: {text}", file=stream)


def replayed_health(log: RunLog) -> dict[str, Any]:
    """The ``health`` object recomputed from the run log alone (equal to the live one when
    every step was logged)."""
    replay, last = Replay(log), None
    for snap, _ in replay.run():
        last = snap
    if last is None:
        return {}
    return replay.health_report(last).summary()


def compare_health(health: dict[str, Any], run_dir: Path) -> tuple[list[str], bool]:
    """Compare a recomputed ``health`` object with the one in the run's summary.json."""
    return compare_object(HEALTH, health, run_dir, "health record")


def compare_object(key: str, recomputed: Any, run_dir: Path, what: str) -> tuple[list[str], bool]:
    """Compare a recomputed summary.json object (``key``) with the run's own: a line for
    ``mresim replay --metrics``, and whether they are equal (none to compare: equal)."""
    path = run_dir / "summary.json"
    try:
        live = json.loads(path.read_text(encoding="utf-8")).get(key)
    except (OSError, ValueError, AttributeError):
        live = None
    if live is None:
        return [f"{what} recomputed (no {key} object in summary.json to compare)"], True
    same = live == json.loads(json.dumps(recomputed))
    verdict = "identical to" if same else "DIFFERENT from"
    return [f"{what} recomputed: {verdict} the one in {path}"], same
