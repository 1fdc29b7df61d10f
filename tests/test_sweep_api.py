"""The Python sweep API (``sweeps/api.py``): ``run_study`` returns the runs (and steps)
tables of a study given as a mapping or a file, resumes a folder without running a run
twice, and refuses a bad study naming the field; docs/sweeps.md's example runs."""

from __future__ import annotations

import re
from pathlib import Path

import pandas as pd
import pytest
import yaml

from mresim_phys.sweeps import run_study
from mresim_phys.sweeps.study import StudyError

ROOT = Path(__file__).resolve().parent.parent


def test_the_docs_example_runs(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    text = (ROOT / "docs" / "sweeps.md").read_text(encoding="utf-8")
    section = text.split("## From Python", 1)[1]
    code = re.search(r"```python\n(.*?)```", section, re.S)
    assert code is not None
    source = code.group(1).replace('"sweeps/quickstart-strategies"', repr(str(tmp_path / "s")))
    monkeypatch.chdir(ROOT)
    scope: dict[str, object] = {}
    exec(compile(source, "docs/sweeps.md", "exec"), scope)
    runs, steps = scope["runs"], scope["steps"]
    assert isinstance(runs, pd.DataFrame) and isinstance(steps, pd.DataFrame)
    assert len(runs) == 6 and (runs["status"] == "done").all()
    assert set(runs["team.strategy"]) == {"frontier", "nearest_frontier"}
    assert {"step", "explored"} <= set(steps.columns)


def test_a_file_a_resume_and_a_bad_study(tmp_path: Path) -> None:
    study = {
        "name": "api",
        "scenarios": [str(ROOT / "scenarios" / "01_quickstart.yaml")],
        "seeds": 2,
        "steps": 30,
    }
    path = tmp_path / "study.yaml"
    path.write_text(yaml.safe_dump(study))
    first = run_study(path, out=tmp_path / "out", workers=1)
    assert isinstance(first, pd.DataFrame) and len(first) == 2
    manifest = (tmp_path / "out" / "manifest.jsonl").read_text()
    again = run_study(study, out=tmp_path / "out", workers=1)  # the same runs: none run again
    assert isinstance(again, pd.DataFrame)
    assert (tmp_path / "out" / "manifest.jsonl").read_text() == manifest
    pd.testing.assert_frame_equal(first, again)
    with pytest.raises(StudyError, match="seedz"):
        run_study({**study, "seedz": 3}, out=tmp_path / "bad")
