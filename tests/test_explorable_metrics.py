"""The explored and known-at-base metrics over the explorable area, their ``_connected``
columns, summary.json's counts, and replays of both (metrics.py, knowledge/coverage.py,
output/runlog.py), as a user runs them from the command line."""

from __future__ import annotations

import csv
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from conftest import csv_row, write_png

from mresim_phys.cli import main
from mresim_phys.columns import Layout
from mresim_phys.metrics import RobotRecord, StepRecord
from mresim_phys.output.runlog import Replay, RunLog, recompute_metrics
from mresim_phys.tracking import Milestones
from mresim_phys.types import RobotSight
from mresim_phys.viewer.replaysource import freeze, thaw
from mresim_phys.world.explorable import explorable_mask

FIXED = ["step", "explored", "known_at_base", "distance", "alive", "links", "comm_bytes"]
FIXED += ["control_links", "control_bytes", "latency_max", "latency_mean"]


def narrow_door_map() -> np.ndarray:
    """60 x 80: outer wall, a wall at columns 40-41 with a 3-cell door (rows 28-30), too
    narrow for a robot of radius 2; a pillar in the left room."""
    occ = np.zeros((60, 80), dtype=bool)
    occ[:2, :] = occ[-2:, :] = occ[:, :2] = occ[:, -2:] = True
    occ[:, 40:42] = True
    occ[28:31, 40:42] = False
    occ[12:16, 20:24] = True
    return occ


def write_scenario(folder: Path, grid: np.ndarray | None = None, **changes: Any) -> Path:
    """Two robots of radius 2 in the left room of :func:`narrow_door_map` (or ``grid``)."""
    write_png(folder / "door.png", narrow_door_map() if grid is None else grid)
    data: dict[str, Any] = {
        "name": "narrow-door",
        "seed": 5,
        "steps": 60,
        "map": {"image": "door.png"},
        "base_station": {"position": [8, 30], "comm_range": 30},
        "team": {"speed": 3, "radius": 2.0, "sensor": {"range": 30}, "comm_range": 30},
        "robots": [
            {"name": "A", "start": [10, 20], "heading_deg": 0},
            {"name": "B", "start": [10, 40], "heading_deg": 0},
        ],
        **changes,
    }
    path = folder / "scenario.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return path


def run(path: Path, out: Path) -> None:
    assert main(["run", str(path), "--out", str(out), "--quiet", "--no-plots"]) == 0


def read_rows(path: Path) -> list[dict[str, str]]:
    with path.open(encoding="utf-8") as handle:
        return list(csv.DictReader(handle))


def test_the_team_explores_what_it_can_see_and_the_old_definition_stays_beside_it(
    tmp_path: Path,
) -> None:
    out = tmp_path / "run"
    run(write_scenario(tmp_path), out)
    header = (out / "metrics.csv").read_text(encoding="utf-8").splitlines()[0].split(",")
    assert header[:13] == [*FIXED, "explored_connected", "known_at_base_connected"]
    assert header[13:15] == ["distance_A", "distance_B"]
    last = read_rows(out / "metrics.csv")[-1]
    assert float(last["explored"]) > 0.85  # the room beyond the door is mostly out of sight
    assert float(last["explored_connected"]) < 0.7
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    free = int(np.count_nonzero(~narrow_door_map()))
    sights = [RobotSight((10.0, 20.0), 2.0, 30.0), RobotSight((10.0, 40.0), 2.0, 30.0)]
    assert summary["connected_cells"] == free
    assert summary["explorable_cells"] == np.count_nonzero(
        explorable_mask(narrow_door_map(), sights)
    )
    assert summary["explorable_cells"] < 0.75 * free
    assert summary["final_explored"] == float(last["explored"])
    assert summary["final_explored_connected"] == float(last["explored_connected"])
    assert summary["final_known_at_base_connected"] == float(last["known_at_base_connected"])
    assert summary["steps_to_explored"]["0.9"] is not None
    assert summary["steps_to_explored_connected"]["0.9"] is None
    assert set(summary["steps_to_known_at_base_connected"]) == {"0.5", "0.9", "0.95"}


def test_replay_gives_both_definitions_byte_for_byte_as_the_world_changes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The door widens at step 10 (the room beyond joins the reachable positions), a
    walker crosses the left room, a pillar falls at step 30: metrics-replayed.csv equals
    metrics.csv, 'latest' beliefs and all."""
    events = [
        {"step": 10, "cells": [40, 24, 42, 28], "occupied": False},
        {"step": 30, "cells": [30, 40, 33, 43]},
    ]
    walker = {"name": "walker", "shape": {"circle": 2}, "motion": {
        "waypoints": [[20, 45], [35, 45]], "speed": 1.0, "mode": "back_and_forth"}}  # fmt: skip
    out = tmp_path / "run"
    run(write_scenario(tmp_path, steps=50, events=events, obstacles=[walker]), out)
    assert main(["replay", str(out), "--metrics"]) == 0
    assert "identical" in capsys.readouterr().out
    assert (out / "metrics-replayed.csv").read_bytes() == (out / "metrics.csv").read_bytes()
    rows = read_rows(out / "metrics.csv")
    assert rows[9]["explored"] != rows[10]["explored"]  # the denominator grew at step 10
    assert "stale" in rows[0]


def test_a_replay_thawed_mid_run_goes_on_with_the_same_metrics(tmp_path: Path) -> None:
    """The viewer's keyframes leave the explorable area out and rebuild it on thaw (maps
    that only grow: a thawed 'latest' coverage miscounts ``stale``, as before)."""
    walker = {"name": "walker", "shape": {"circle": 2}, "motion": {
        "waypoints": [[20, 45], [35, 45]], "speed": 1.0, "mode": "back_and_forth"}}  # fmt: skip
    out, grow = tmp_path / "run", {"belief": "grow"}
    run(write_scenario(tmp_path, steps=30, obstacles=[walker], simulation=grow), out)
    log = RunLog.open(out / "log")
    rows = [csv_row(record) for record in recompute_metrics(log)]
    replay = Replay(log)
    steps = list(log.records())
    for line, chunk, j in steps[:12]:
        replay.step(line, chunk, j)
    thawed = thaw(freeze(replay), log)
    assert [csv_row(thawed.step(*entry)[1]) for entry in steps[12:]] == rows[12:]
    assert thawed.explorable is not None and thawed.coverage.reachable is thawed.explorable.mask


def test_a_log_older_than_the_explorable_area_replays_the_old_metrics(tmp_path: Path) -> None:
    out = tmp_path / "run"
    run(write_scenario(tmp_path, steps=25), out)
    meta_file = out / "log" / "meta.json"
    meta = json.loads(meta_file.read_text(encoding="utf-8"))
    del meta["sights"]
    meta["version"] = 4
    meta_file.write_text(json.dumps(meta), encoding="utf-8")
    live = read_rows(out / "metrics.csv")
    replayed = list(recompute_metrics(RunLog.open(out / "log")))
    assert [r.explored_connected for r in replayed] == [None] * 26
    assert [repr(r.explored) for r in replayed] == [row["explored_connected"] for row in live]
    old = [repr(r.known_at_base) for r in replayed]
    assert old == [row["known_at_base_connected"] for row in live]
    old_layout = Layout.of(["A", "B"], latest=False, faults=False, connected=False)
    assert len(old_layout.row(replayed[0])) == len(live[0]) - 2


def test_a_damaged_sights_entry_is_a_clear_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "run"
    run(write_scenario(tmp_path, steps=3), out)
    meta_file = out / "log" / "meta.json"
    meta = json.loads(meta_file.read_text(encoding="utf-8"))
    meta["sights"][0]["seeds"] = [[600, 2]]
    meta_file.write_text(json.dumps(meta), encoding="utf-8")
    assert main(["replay", str(out), "--metrics"]) == 2
    assert "seed outside the map" in capsys.readouterr().err


def record(explored: float, connected: float | None, step: int = 1) -> StepRecord:
    robots = (RobotRecord("A", 1.0, "active"),)
    return StepRecord(step, explored, explored, 1.0, 1, 0, robots, explored_connected=connected,
                      known_at_base_connected=connected)  # fmt: skip


def test_rows_put_the_connected_columns_after_the_fixed_ones() -> None:
    layout = Layout.of(["A"], latest=False, faults=False)
    row, header = layout.row(record(0.5, 0.25)), layout.header()
    assert len(row) == len(header) and row[header.index("explored_connected")] == "0.25"
    old = Layout.of(["A"], latest=False, faults=False, connected=False)
    assert old.header() == [*FIXED, "distance_A", "state_A", "base_contact_A"]
    assert len(old.row(record(0.5, None))) == len(header) - 2


def test_milestones_follow_both_definitions() -> None:
    milestones = Milestones()
    for step, (explored, connected) in enumerate([(0.4, 0.3), (0.92, 0.6), (0.96, 0.91)]):
        milestones.update(record(explored, connected, step))
    assert milestones.explored == {"0.5": 1, "0.9": 1, "0.95": 2}
    assert milestones.explored_connected == {"0.5": 1, "0.9": 2, "0.95": None}
    milestones.update(record(1.0, None, 3))  # a replay of an old log: no second column
    assert milestones.known_at_base_connected == {"0.5": 1, "0.9": 2, "0.95": None}
