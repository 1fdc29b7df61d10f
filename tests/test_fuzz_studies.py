"""Malformed study files never crash: each is accepted (checked, its first runs run) or
refused with one message naming the file, in a few seconds at most.

Hypothesis mutates valid studies (``tools/fuzz_studies.py`` holds the generators, the
judge and the child process that times each file); the classes of mistake it covers are
pinned one by one in ``tests/test_study_files.py`` and ``tests/test_plugins_family.py``.
"""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from tool_modules import load_tool

ROOT = Path(__file__).resolve().parent.parent


fuzz = load_tool("fuzz_studies")
GENERATED = 250  # files generated in the suite; tools/fuzz_studies.py runs more


def test_generated_studies_are_accepted_or_refused_with_a_message(tmp_path: Path) -> None:
    tally = fuzz.fuzz(GENERATED, tmp_path, seed=None)  # derandomized: reproducible
    counts = tally.counts
    assert not tally.crashes, "\n\n".join(f"{text}\n{detail}" for text, detail in tally.crashes)
    assert sum(counts.values()) >= GENERATED
    assert counts["accepted"] >= 10 and counts["rejected"] >= 100, counts  # both paths


def test_the_judge_counts_an_exception_as_a_crash(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from mresim_phys.sweeps import expand

    fuzz.prepare(tmp_path)
    text = yaml.safe_dump(fuzz.BASES[0], sort_keys=False)
    assert fuzz.check_text(text, tmp_path, 1).kind == "accepted"

    def broken(*args: object) -> None:
        raise KeyError("a bug")

    monkeypatch.setattr(expand, "expand_arms", broken)
    outcome = fuzz.check_text(text, tmp_path, 2)
    assert outcome.kind == "crash" and "KeyError: 'a bug'" in outcome.detail
