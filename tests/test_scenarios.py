"""Every shipped scenario validates and runs headless (as Mesa smoke-runs its examples).

Whole runs (golden results, 90 % within the cap) are in test_golden.py.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from mresim_phys import Simulation
from mresim_phys.cli import main

SCENARIOS = sorted((Path(__file__).parent.parent / "scenarios").glob("*.yaml"))


def test_there_are_shipped_scenarios() -> None:
    assert len(SCENARIOS) >= 5


@pytest.mark.parametrize("path", SCENARIOS, ids=lambda p: p.stem)
def test_shipped_scenario_runs(path: Path, tmp_path: Path) -> None:
    assert main(["validate", str(path)]) == 0
    assert main(["run", str(path), "--steps", "15", "--out", str(tmp_path), "--quiet"]) == 0
    assert (tmp_path / "metrics.csv").read_text().count("\n") >= 2
    sim = Simulation.from_yaml(path, steps=5)
    last = sim.run()
    assert 0 < last.explored <= 1
