"""``mresim robustness`` (sweeps, shortcut): how robust is a strategy to robot failure.

Builds the study "the scenario x strategies x k robots failing x seeds" (``failures``:
k robots of the team fail at random steps drawn per seed, the same for every strategy;
``sweeps/failures.py``), runs it as ``mresim sweep`` would and compares it as
``mresim compare --by strategy,failures`` would, with the first strategy without
failures as the reference arm. The degradation figure answers the question.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from mresim_phys.scenario.readers import read_yaml_mapping
from mresim_phys.sweeps.study import FAILURES, parse_study


def robustness_study(
    scenario: Path,
    strategies: list[str],
    failures: list[int],
    seeds: int,
    steps: int | None = None,
    window: tuple[float, float] | None = None,
) -> tuple[dict[str, Any], str]:
    """The study's data and its YAML text (scenario path made absolute)."""
    name = read_yaml_mapping(scenario).get("name") or scenario.stem
    data: dict[str, Any] = {
        "name": f"{name}-robustness",
        "scenarios": [str(Path(scenario).resolve())],
        "axes": {"team.strategy": list(strategies), FAILURES: list(failures)},
        "seeds": seeds,
        "reference": {"team.strategy": strategies[0], FAILURES: failures[0]},
    }
    if steps is not None:
        data["steps"] = steps
    if window is not None:
        data["failure_window"] = list(window)
    parse_study(data, f"mresim robustness {scenario}")  # the flags' values, checked
    return data, yaml.safe_dump(data, sort_keys=False)
