"""``mresim robustness`` (sweeps, shortcut): how robust is a strategy to robot failure.

Builds the study "the scenario x strategies x k robots failing x seeds" (``failures``:
k robots of the team fail at random steps drawn per seed, the same for every strategy;
``sweeps/failures.py``), runs it as ``mresim sweep`` would and compares it as
``mresim compare --by strategy,failures`` would, with the first strategy without
failures as the reference arm. The degradation figure answers the question. A strategy
or failure count given twice (``--strategies frontier,frontier``) would run the same arms
twice: it is refused, naming the flag.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from mresim_phys.scenario.readers import read_yaml_mapping
from mresim_phys.scenario.schema import MAX_NAME, check_name
from mresim_phys.sweeps.study import FAILURES, StudyError, parse_study, repeated

SUFFIX = "-robustness"


def robustness_study(
    scenario: Path,
    strategies: list[str],
    failures: list[int],
    seeds: int,
    steps: int | None = None,
    window: tuple[float, float] | None = None,
) -> tuple[dict[str, Any], str]:
    """The study's data and its YAML text (scenario path made absolute)."""
    source = f"mresim robustness {scenario}"
    check_flags(strategies, failures, source)
    data: dict[str, Any] = {
        "name": study_name(scenario),
        "scenarios": [str(Path(scenario).resolve())],
        "axes": {"team.strategy": list(strategies), FAILURES: list(failures)},
        "seeds": seeds,
        "reference": {"team.strategy": strategies[0], FAILURES: failures[0]},
    }
    if steps is not None:
        data["steps"] = steps
    if window is not None:
        data["failure_window"] = list(window)
    parse_study(data, source)  # the flags' values, checked
    return data, yaml.safe_dump(data, sort_keys=False)


def check_flags(strategies: list[str], failures: list[int], source: str) -> None:
    """StudyError naming the flag that gives a value twice (the same arms would run twice)."""
    for flag, values in (("--strategies", strategies), ("--failures", failures)):
        if repeated(values):
            raise StudyError(
                f"{source}: {flag} gives {', '.join(map(str, repeated(values)))} more than"
                " once, which would run the same arms twice; give each value once."
            )


def study_name(scenario: Path) -> str:
    """``<scenario name>-robustness`` (the sweep folder's default name), shortened to a
    valid name (the scenario's own name is checked with the scenario, not here)."""
    keep = MAX_NAME - len(SUFFIX)
    found = read_yaml_mapping(scenario).get("name")
    stems = [c[:keep] for c in (found, scenario.stem) if isinstance(c, str)]
    return next((s for s in stems if is_name(s)), "scenario") + SUFFIX


def is_name(text: str) -> bool:
    """Whether ``text`` is a valid scenario (and study) name."""
    try:
        check_name(text)
    except ValueError:
        return False
    return True
