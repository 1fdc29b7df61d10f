"""A robot's known area (``knowledge/known_area.py``): every FREE cell of its map lies in it,
through scans, merges, drift and noisy lasers, so a replan's FREE box found inside it is the
whole grid's."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mresim_phys.knowledge.known_area import CHECK, KNOWN_AREA, KnownArea, free_box, free_count
from mresim_phys.planning.grid import bbox
from mresim_phys.scenario.load import load_scenario
from mresim_phys.sim import Simulation
from mresim_phys.types import FREE, OCCUPIED

SCENARIOS = Path(__file__).resolve().parent.parent / "scenarios"


@pytest.mark.parametrize(
    "name",
    [
        "02_office_frontier",
        "11_library_8_robots",
        "29_library_drift_scan_matching",
        "31_office_noisy_laser",
    ],
)
def test_every_free_cell_of_every_robot_lies_in_its_known_area(
    name: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Replans check their box against the whole grid (the check mode raises on a FREE cell
    outside), and after each step every robot's map is checked too."""
    monkeypatch.setenv(CHECK, "1")
    scenario = load_scenario(SCENARIOS / f"{name}.yaml")
    sim = Simulation(scenario.model_copy(update={"steps": 40}))
    for _ in range(40):
        sim.step()
        for robot in sim.robots:
            known = KNOWN_AREA.value_in(robot.features)
            whole = bbox(robot.belief == FREE)
            assert whole is None or (
                known is not None
                and known[0] <= whole[0] and whole[1] <= known[1]
                and known[2] <= whole[2] and whole[3] <= known[3]
            )  # fmt: skip


def test_the_box_is_found_inside_the_known_area() -> None:
    belief = np.zeros((50, 60), np.uint8)
    belief[10:20, 30:45] = FREE
    belief[25, 5] = OCCUPIED
    known = KnownArea()
    assert free_box(belief, {KNOWN_AREA.key: known.box}) is None  # nothing written yet
    known.grow((8, 22, 28, 50))
    known.grow((24, 27, 4, 7))
    assert known.box == (8, 27, 4, 50)
    assert free_box(belief, {KNOWN_AREA.key: known.box}) == (10, 20, 30, 45)
    assert free_box(belief, {}) == (10, 20, 30, 45)  # a view without one: the whole grid
    assert free_count(belief, {KNOWN_AREA.key: known.box}) == free_count(belief, {}) == 150
    assert free_count(belief, {KNOWN_AREA.key: None}) == 0 == free_count(belief * 0, {})


def test_the_check_mode_catches_a_free_cell_outside_the_known_area(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setenv(CHECK, "1")
    belief = np.zeros((50, 60), np.uint8)
    belief[10:20, 30:45] = FREE
    with pytest.raises(AssertionError, match="outside the known area"):
        free_box(belief, {KNOWN_AREA.key: (10, 20, 30, 40)})
    with pytest.raises(AssertionError, match="outside the known area"):
        free_count(belief, {KNOWN_AREA.key: (10, 20, 30, 40)})


def test_the_mission_complete_rule_counts_every_free_cell(monkeypatch: pytest.MonkeyPatch) -> None:
    """The rule counts a robot's FREE cells inside its known area at every replan from
    ``done_after`` on; in check mode each count is the whole grid's, and the rule still
    sends robots out of the base's reach home (its fraction made small enough to be met
    early)."""
    monkeypatch.setenv(CHECK, "1")
    strategy = {"name": "frontier", "params": {"done_after": 5, "done_fraction": 0.05}}
    out_of_reach = {"team.comm_range": 5, "base_station.comm_range": 5}
    sim = Simulation.from_yaml(
        SCENARIOS / "11_library_8_robots.yaml",
        steps=30,
        **{"team.strategy": strategy, **out_of_reach},
    )
    sim.run()
    assert any(r.strategy.parts.done.was_met for r in sim.robots)  # type: ignore[attr-defined]
