"""Recorders (output edge): what a run leaves on disk.

:class:`RunWriter` writes, into the run folder (default
``runs/<name>/seed-<seed>/``): ``scenario.yaml`` (the fully resolved scenario,
every default filled in), ``metrics.csv`` (one row per step, written as the run
goes) and ``summary.json`` at the end. ``metrics.csv`` holds no wall-clock
values, so the same scenario and seed give a byte-identical file.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path
from typing import Any

import yaml

from mresim_phys.metrics import CommTotals, Milestones, StepRecord, csv_header
from mresim_phys.scenario.schema import Scenario


def default_run_dir(scenario: Scenario) -> Path:
    """``runs/<name>/seed-<seed>`` under the current folder."""
    return Path("runs") / scenario.name / f"seed-{scenario.seed}"


def scenario_yaml(scenario: Scenario) -> str:
    """The resolved scenario as YAML (keys in schema order)."""
    return yaml.safe_dump(scenario.model_dump(mode="json"), sort_keys=False)


class RunWriter:
    """Streams ``metrics.csv`` during a run and writes ``summary.json`` when closed."""

    def __init__(self, out_dir: Path, scenario: Scenario) -> None:
        self.out_dir = out_dir
        out_dir.mkdir(parents=True, exist_ok=True)
        (out_dir / "scenario.yaml").write_text(scenario_yaml(scenario), encoding="utf-8")
        self._file = (out_dir / "metrics.csv").open("w", newline="", encoding="utf-8")
        self._csv = csv.writer(self._file, lineterminator="\n")
        self._csv.writerow(csv_header([r.name for r in scenario.robots]))

    def on_step(self, record: StepRecord) -> None:
        """Append one row."""
        self._csv.writerow(record.csv_row())

    def close(self) -> None:
        """Flush and close ``metrics.csv``."""
        self._file.close()

    def write_summary(self, summary: dict[str, Any]) -> Path:
        """Write ``summary.json`` and return its path."""
        path = self.out_dir / "summary.json"
        path.write_text(json.dumps(summary, indent=2) + "\n", encoding="utf-8")
        return path


def summarise(
    scenario: Scenario,
    last: StepRecord,
    milestones: Milestones,
    wall_time_s: float,
    stop_reason: str,
    comm: CommTotals | None = None,
) -> dict[str, Any]:
    """The run's headline numbers for ``summary.json``."""
    return {
        "name": scenario.name,
        "seed": scenario.seed,
        "steps": last.step,
        "stop_reason": stop_reason,
        "wall_time_s": round(wall_time_s, 3),
        "steps_per_second": round(last.step / wall_time_s, 2) if wall_time_s > 0 else None,
        "final_explored": last.explored,
        "final_known_at_base": last.known_at_base,
        "steps_to_explored": milestones.explored,
        "steps_to_known_at_base": milestones.known_at_base,
        "total_distance": last.distance,
        "alive": last.alive,
        "robots": {
            r.name: {"distance": r.distance, "state": r.state, "base_contact": r.base_contact}
            for r in last.robots
        },
        "communication": (comm or CommTotals()).summary(),
    }
