"""Per-robot features (``features.py``): a feature's state, value, log codec, label, hover
entry and column, shown by the battery (``faults/battery.py``) and by a feature of a test's
own registered in code."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from conftest import write_scenario
from test_runlog import assert_same_snapshot, record_run

from mresim_phys import Simulation
from mresim_phys.columns import Layout
from mresim_phys.faults.battery import BATTERY
from mresim_phys.features import FEATURES, FeatureList, RobotFeature
from mresim_phys.output.logformat import AGENT_LINE, decode_line, encode_line
from mresim_phys.output.runlog import RunLog, recompute_metrics
from mresim_phys.render.draw import robot_label
from mresim_phys.snapshot import AgentSnapshot
from mresim_phys.viewer.frames import agent_row

BATTERY_SPEC = {"capacity": 60, "per_cell": 1.0, "per_scan": 0.1, "robots": ["B"]}


def battery_scenario(folder: Path, steps: int = 30) -> Path:
    return write_scenario(folder, faults={"battery": BATTERY_SPEC}, steps=steps)


def test_the_battery_is_seen_recorded_and_labelled_only_where_a_robot_has_one(
    tmp_path: Path,
) -> None:
    sim = Simulation.from_yaml(battery_scenario(tmp_path))
    for _ in range(5):
        sim.step()
    a, b = sim.robot("A"), sim.robot("B")
    level = BATTERY.value_in(b.features)
    assert level is not None and 0 < level < 1 and BATTERY.value_in(a.features) is None
    assert BATTERY.of(sim.view_of(b)) == level and BATTERY.of(sim.view_of(a)) is None
    snap = {agent.name: agent for agent in sim.snapshot().agents}
    recorded = {
        name: {k: v for k, v in s.features.items() if k != "health"} for name, s in snap.items()
    }
    assert recorded["B"] == {"battery": level} and recorded["A"] == {}
    assert robot_label(snap["B"]) == f"B {level:.0%}" and robot_label(snap["A"]) == "A"
    assert agent_row(snap["B"], (0.0, 0.0), 3.0)["battery"] == round(level, 4)
    assert agent_row(snap["A"], (0.0, 0.0), 3.0)["battery"] is None
    line = encode_line(AGENT_LINE, snap["B"])
    assert line["battery"] == level and "battery" not in encode_line(AGENT_LINE, snap["A"])


def test_the_battery_replays_and_its_column_is_recomputed(tmp_path: Path) -> None:
    snaps, _, _ = record_run(battery_scenario(tmp_path), tmp_path / "log", 30)
    log = RunLog.open(tmp_path / "log")
    for got, want in zip(log.snapshots(), snaps, strict=True):
        assert_same_snapshot(got, want)
    sim = Simulation.from_yaml(battery_scenario(tmp_path))
    layout = Layout.of(["A", "B"], latest=False, faults=True, extra=["robot_battery"])
    live = [layout.row(sim.record)] + [layout.row(sim.step()) for _ in range(30)]
    assert [layout.row(r) for r in recompute_metrics(log)] == live
    header = layout.header()
    assert header[-2:] == ["battery_A", "battery_B"]
    levels = [float(row[-1]) for row in live]
    assert all(row[-2] == "" for row in live) and levels == sorted(levels, reverse=True)
    assert 0 <= levels[-1] < levels[0] <= 1


@dataclass
class Beacon:
    """A test feature's state: how many pings a robot sent."""

    pings: int


class BeaconFeature(RobotFeature[Beacon, int]):
    key = "beacon"

    def value(self, state: Beacon) -> int:
        return state.pings

    def label(self, value: int) -> str:
        return f" ({value} pings)"


def test_a_feature_registered_in_code_rides_in_views_snapshots_logs_and_labels(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    features = FeatureList({"battery": "mresim_phys.faults.battery:BATTERY"})
    beacon = features.register(BeaconFeature())
    monkeypatch.setattr("mresim_phys.features.FEATURES", features)
    for module in ("agent_views", "output.logformat", "render.draw", "viewer.frames", "sim"):
        monkeypatch.setattr(f"mresim_phys.{module}.FEATURES", features)
    sim = Simulation.from_yaml(battery_scenario(tmp_path))
    sim.robot("A").features["beacon"] = Beacon(3)
    sim.step()
    assert beacon.of(sim.view_of(sim.robot("A"))) == 3
    snap: AgentSnapshot = sim.snapshot().agents[1]
    assert snap.features == {"beacon": 3} and robot_label(snap) == "A (3 pings)"
    line: dict[str, Any] = encode_line(AGENT_LINE, snap)
    assert line["beacon"] == 3
    assert decode_line(AGENT_LINE, AgentSnapshot, line, 3)["features"] == {"beacon": 3}
    assert sim.record.robots[0].features == {"beacon": 3}


def test_a_feature_key_is_taken_once() -> None:
    with pytest.raises(ValueError, match="already registered"):
        FeatureList({"battery": "mresim_phys.faults.battery:BATTERY"}).register(BATTERY)
    assert [f.key for f in FEATURES.all()][:2] == ["parts", "battery"]  # built-ins first
