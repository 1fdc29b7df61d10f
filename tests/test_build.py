"""The composition root: one place reads the schema; a run rebuilds from a pickled Scenario."""

from __future__ import annotations

import ast
import multiprocessing
import pickle
from collections.abc import Callable
from pathlib import Path

from mresim_phys import Simulation
from mresim_phys.metrics import StepRecord
from mresim_phys.scenario.load import load_scenario

ScenarioFile = Callable[..., Path]
PACKAGE = Path(__file__).parent.parent / "mresim_phys"
RUNTIME = [
    "agents.py",
    "motion.py",
    "metrics.py",
    "event_context.py",
    "sim.py",
    "world",
    "knowledge",
    "comms",
    "strategies",
    "planning",
]


def imported_modules(path: Path) -> set[str]:
    """Every module a file imports (absolute names), at any depth of the file."""
    names: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.module:
            names.add(node.module)
            names.update(f"{node.module}.{a.name}" for a in node.names)
        elif isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
    return names


def test_the_runtime_never_imports_the_scenario_schema() -> None:
    files = [p for entry in RUNTIME for p in sorted((PACKAGE / entry).rglob("*.py"))]
    files += [PACKAGE / entry for entry in RUNTIME if entry.endswith(".py")]
    offenders = {
        str(f.relative_to(PACKAGE)): sorted(
            m for m in imported_modules(f) if m.startswith("mresim_phys.scenario")
        )
        for f in files
    }
    assert {f: m for f, m in offenders.items() if m} == {}


def records_of(scenario_bytes: bytes, steps: int) -> list[StepRecord]:
    """Run a pickled scenario for ``steps`` steps (in whichever process calls this)."""
    sim = Simulation(pickle.loads(scenario_bytes))
    return [sim.record] + [sim.step() for _ in range(steps)]


def test_a_run_rebuilt_in_another_process_from_a_pickled_scenario_is_identical(
    scenario_file: ScenarioFile,
) -> None:
    scenario = load_scenario(scenario_file(events=[{"step": 4, "fail": "B", "part": "drive"}]))
    payload = pickle.dumps(scenario)
    here = records_of(payload, 12)
    with multiprocessing.get_context("spawn").Pool(1) as pool:
        there = pool.apply(records_of, (payload, 12))
    assert here == there
