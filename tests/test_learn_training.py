"""The learning example (``examples/train_ppo.py``): PPO on the single-agent environment
learns a policy whose return beats a random valid choice; its ONNX export then runs as the
``policy`` strategy in a robustness study next to ``frontier``."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "train_ppo.py"


@pytest.mark.slow
def test_ppo_beats_a_random_choice_and_runs_in_a_robustness_study(tmp_path: Path) -> None:
    out = tmp_path / "ppo"
    command = [sys.executable, str(EXAMPLE), "--timesteps", "6000", "--eval", "6"]
    done = subprocess.run(
        [*command, "--study", "2", "--out", str(out)], capture_output=True, text=True, check=True
    )
    found = re.search(
        r"random valid choice (-?[\d.]+), untrained (-?[\d.]+), trained (-?[\d.]+)", done.stdout
    )
    assert found is not None, done.stdout
    random_valid, _, trained = (float(v) for v in found.groups())
    assert trained > random_valid + 2.0
    curve = pd.read_csv(out / "curve.csv")
    assert len(curve) > 20
    runs = pd.read_parquet(out / "study" / "runs.parquet")
    assert len(runs) == 8 and (runs["status"] == "done").all()
    assert runs["team.strategy"].astype(str).str.contains("policy").sum() == 4
