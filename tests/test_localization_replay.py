"""The localisation summary recomputed by ``mresim replay --metrics`` from the run log alone."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from mresim_phys.cli import main
from mresim_phys.localization.feature import LOCALIZATION, PoseBelief

DRIFT = {
    "odometry": {"alpha": [0.002, 0.00001, 0.002, 0.00001]},
    "corrections": [{"kind": "base", "within": 30}, {"kind": "teammate"}],
}


def test_replay_recomputes_the_localization_summary_from_the_log(
    scenario_file: Any, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = scenario_file(team={**yaml_team(), "localization": DRIFT}, steps=40)
    out = tmp_path / "run"
    assert main(["run", str(path), "--out", str(out), "--quiet", "--no-plots"]) == 0
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))["localization"]
    assert sum(sum(r["corrections"].values()) for r in summary["robots"].values()) > 0
    assert main(["replay", str(out), "--metrics"]) == 0
    printed = capsys.readouterr().out
    assert "localization recomputed: identical" in printed


def test_a_belief_logged_before_the_counts_of_corrections_reads_as_none_counted() -> None:
    belief = PoseBelief((1.0, 2.0, 0.5), (1.0, 0.0, 1.0, 0.0, 0.0, 0.1), 0.7, 0.02, (3, 0, 2, 0))
    raw = LOCALIZATION.encode(belief)
    assert LOCALIZATION.decode(raw) == belief
    old = LOCALIZATION.decode(raw[:11])
    assert old.fixes == (0, 0, 0, 0) and old.corrections() == {}
    assert belief.corrections() == {"base": 3, "teammate": 2}


def yaml_team() -> dict[str, Any]:
    return {"speed": 2, "radius": 1.0, "sensor": {"range": 30}, "comm_range": 20}


def test_a_localization_summary_the_log_does_not_give_is_reported_different(
    scenario_file: Any, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = scenario_file(team={**yaml_team(), "localization": DRIFT}, steps=20)
    out = tmp_path / "run"
    assert main(["run", str(path), "--out", str(out), "--quiet", "--no-plots"]) == 0
    summary_path = out / "summary.json"
    summary = json.loads(summary_path.read_text(encoding="utf-8"))
    summary["localization"]["team"]["mean_error"] += 1.0
    summary_path.write_text(json.dumps(summary), encoding="utf-8")
    assert main(["replay", str(out), "--metrics"]) != 0
    assert "localization recomputed: DIFFERENT" in capsys.readouterr().out
