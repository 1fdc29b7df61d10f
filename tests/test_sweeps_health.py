"""The run-health totals in the sweep tables (sweeps/tables.py) and in compare's report."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
from conftest import write_study

from mresim_phys.cli import main
from mresim_phys.sweeps.tables import flatten_summary

COLUMNS = [
    "robots_idle_with_frontier",
    "idle_robot_steps",
    "stuck_robot_steps",
    "waiting_robot_steps",
    "robots_fruitless",
    "fruitless_robot_steps",
]


def test_the_health_totals_are_flat_columns_and_the_rest_of_the_record_is_not() -> None:
    health = {"robots_idle_with_frontier": 1, "idle_robot_steps": 40, "stuck_robot_steps": 2}
    health |= {"waiting_robot_steps": 7, "robots_fruitless": 1, "fruitless_robot_steps": 120}
    summary = {"steps": 50, "health": {**health, "robots": {"A": {}}, "warnings": ["x"]}}
    assert flatten_summary(summary) == {"steps": 50, **health}


def test_a_sweep_tabulates_and_compares_idle_robots(tmp_path: Path) -> None:
    """Parked robots (they never move) against random walkers, 2 seeds of 25 steps."""
    axes = {"team.strategy": ["random_walk", "health_plugins:Parked"]}
    study = write_study(tmp_path, steps=25, axes=axes)
    out = tmp_path / "sweep"
    assert main(["sweep", str(study), "--out", str(out), "--quiet", "--workers", "1"]) == 0
    runs = pd.read_parquet(out / "runs.parquet")
    for row in runs.itertuples():
        health = json.loads((out / "runs" / row.run_id / "summary.json").read_text())["health"]
        assert [getattr(row, c) for c in COLUMNS] == [health[c] for c in COLUMNS]
    parked = runs[runs["team.strategy"] == "health_plugins:Parked"]
    assert (parked["robots_idle_with_frontier"] == 2).all()  # the quickstart's two robots
    assert (parked["idle_robot_steps"] == 50).all()
    walkers = runs[runs["team.strategy"] == "random_walk"]
    assert (walkers["robots_idle_with_frontier"] == 0).all()
    assert main(["compare", str(out)]) == 0
    report = (out / "compare" / "report.md").read_text(encoding="utf-8")
    for column in COLUMNS:
        assert f"## {column}\n" in report
    section = report.split("## idle_robot_steps\n", 1)[1].split("\n## ", 1)[0]
    assert "| strategy=health_plugins:Parked | 2 | 50 | 50 |" in section
