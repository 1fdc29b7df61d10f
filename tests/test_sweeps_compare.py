"""``mresim compare`` and ``mresim robustness``: figures, and report numbers a pandas and
scipy computation in the test gives too."""

from __future__ import annotations

import contextlib
import io
import math
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from mresim_phys.cli import main

REPO = Path(__file__).resolve().parent.parent
QUICKSTART = REPO / "scenarios" / "01_quickstart.yaml"


@pytest.fixture(scope="module")
def robustness_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    """``mresim robustness`` on the quickstart: frontier vs random_walk x 0/1 failures x 3
    seeds, 30 steps (12 runs), swept and compared; the folder and what it printed."""
    out = tmp_path_factory.mktemp("robust") / "sweep"
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        code = main(
            [
                "robustness",
                str(QUICKSTART),
                "--strategies",
                "frontier,random_walk",
                "--failures",
                "0,1",
                "--seeds",
                "3",
                "--steps",
                "30",
                "--fail-between",
                "0.1,0.5",
                "--out",
                str(out),
                "--workers",
                "2",
                "--quiet",
                "--svg",
            ]
        )
    assert code == 0
    return out, printed.getvalue()


@pytest.fixture(scope="module")
def robustness(robustness_run: tuple[Path, str]) -> Path:
    """The robustness sweep's folder."""
    return robustness_run[0]


def report_rows(text: str, metric: str) -> dict[str, list[str]]:
    """The per-arm table of ``metric`` in report.md: arm -> its cells."""
    section = text.split(f"## {metric}\n", 1)[1].split("\n## ", 1)[0]
    tables = re.findall(r"((?:^\|.*\|\n)+)", section, flags=re.MULTILINE)
    rows = [line.strip("|").split(" | ") for line in tables[0].splitlines()[2:]]
    return {cells[0].strip(): [c.strip() for c in cells[1:]] for cells in rows}


def pair_rows(text: str, metric: str) -> dict[str, list[str]]:
    """The paired-differences table of ``metric`` in report.md."""
    section = text.split(f"## {metric}\n", 1)[1].split("\n## ", 1)[0]
    tables = re.findall(r"((?:^\|.*\|\n)+)", section, flags=re.MULTILINE)
    rows = [line.strip("|").split(" | ") for line in tables[1].splitlines()[2:]]
    return {cells[0].strip(): [c.strip() for c in cells[1:]] for cells in rows}


def close(shown: str, value: float) -> bool:
    """A report cell (four significant digits) shows ``value``."""
    return float(shown) == pytest.approx(value, rel=1e-3, abs=1e-9)


def test_robustness_writes_the_figures_and_report(robustness: Path) -> None:
    compare = robustness / "compare"
    names = ("curves", "distribution_steps_to_explored_90", "degradation_steps_to_explored_90")
    for name in (*names, "contrast_auc_known_at_base"):
        assert (compare / f"{name}.png").stat().st_size > 5000
        assert (compare / f"{name}.svg").is_file()
    page = (compare / "report.html").read_text(encoding="utf-8")
    assert page.count("data:image/png;base64,") == 4 and "<table>" in page
    runs = pd.read_parquet(robustness / "runs.parquet")
    assert len(runs) == 12 and set(runs["failures"]) == {0, 1}
    assert (runs["failed_robots"] == runs["failures"]).all()  # each drawn failure happened


def test_report_numbers_match_pandas_and_scipy(robustness: Path) -> None:
    runs = pd.read_parquet(robustness / "runs.parquet")
    text = (robustness / "compare" / "report.md").read_text(encoding="utf-8")
    rows = report_rows(text, "final_explored")
    for (strategy, k), group in runs.groupby(["team.strategy", "failures"]):
        values = group["final_explored"].to_numpy()
        n, mean = len(values), values.mean()
        half = stats.t.ppf(0.975, n - 1) * values.std(ddof=1) / math.sqrt(n)
        cells = rows[f"strategy={strategy}, failures={k}"]
        assert cells[0] == str(n) and close(cells[1], mean) and close(cells[2], np.median(values))
        low, high = cells[3].strip("[]").split(", ")
        assert close(low, mean - half) and close(high, mean + half)
        assert cells[4] == "0"  # failed
    reference = runs[(runs["team.strategy"] == "frontier") & (runs["failures"] == 0)]
    other = runs[(runs["team.strategy"] == "random_walk") & (runs["failures"] == 0)]
    both = other.merge(reference, on=["scenario", "seed"], suffixes=("", "_ref"))
    diffs = (both["final_explored"] - both["final_explored_ref"]).to_numpy()
    cells = pair_rows(text, "final_explored")["strategy=random_walk, failures=0"]
    assert cells[0] == "3" and close(cells[1], diffs.mean()) and close(cells[2], np.median(diffs))
    assert close(cells[4], stats.wilcoxon(diffs).pvalue)
    steps = report_rows(text, "steps_to_explored_90")
    censored = runs["steps_to_explored_90"].isna().sum()
    assert sum(int(c[2]) for c in steps.values()) == censored  # not reached, counted
    assert all(c[6] == "0" for c in steps.values())  # no run failed


def test_compare_by_one_axis_and_its_errors(
    robustness: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(
        [
            "compare",
            str(robustness),
            "--by",
            "strategy",
            "--metric",
            "auc_explored",
            "--out",
            str(tmp_path / "c"),
            "--reference",
            "random_walk",
        ]
    )
    assert code == 0
    text = (tmp_path / "c" / "report.md").read_text(encoding="utf-8")
    assert "reference arm strategy=random_walk" in text and "pairs share scenario, seed," in text
    assert set(report_rows(text, "auc_explored")) == {"strategy=frontier", "strategy=random_walk"}
    with pytest.raises(SystemExit) as bad:  # argparse: one line naming the flag, status 2
        main(["compare", str(robustness), "--detect", "0"])
    assert bad.value.code == 2 and "expected a number > 0" in capsys.readouterr().err
    assert main(["compare", str(robustness), "--by", "stratgy"]) == 2
    assert "did you mean 'strategy'" in capsys.readouterr().err.lower()
    assert main(["compare", str(tmp_path)]) == 2
    assert "not a finished sweep folder" in capsys.readouterr().err


def section_of(text: str, metric: str) -> str:
    """The report's section of ``metric``."""
    return text.split(f"## {metric}\n", 1)[1].split("\n## ", 1)[0]


def test_a_censored_time_is_never_averaged_and_its_share_is_shown(robustness: Path) -> None:
    """The quickstart's 30-step runs mostly never reach the thresholds: the report gives
    Kaplan-Meier medians and the share not reached, no mean and no t-interval."""
    runs = pd.read_parquet(robustness / "runs.parquet")
    text = (robustness / "compare" / "report.md").read_text(encoding="utf-8")
    for metric in ("steps_to_explored_90", "steps_to_known_at_base_90"):
        assert runs[metric].isna().mean() > 0.5  # censored-heavy: the case that matters
        section = section_of(text, metric)
        head = section.split("| arm |", 1)[1].splitlines()[0]
        assert "mean" not in head and "share not reached" in head
        assert "mean diff" not in section and "log-rank" in section
        for (strategy, k), group in runs.groupby(["team.strategy", "failures"]):
            cells = report_rows(text, metric)[f"strategy={strategy}, failures={k}"]
            share = group[metric].isna().mean()
            assert cells[3] == f"{share:.0%}"
            imputed = group[metric].fillna(group["steps"] + 1).mean()
            assert f"{imputed:.4g}" not in cells  # the old made-up mean is nowhere


def test_the_robustness_headline_is_the_paired_contrast(
    robustness_run: tuple[Path, str],
) -> None:
    folder, printed = robustness_run
    runs = pd.read_parquet(folder / "runs.parquet").set_index(["team.strategy", "failures", "seed"])
    value = runs["auc_known_at_base"]
    contrast = np.array(
        [
            (value["frontier", 1, s] - value["frontier", 0, s])
            - (value["random_walk", 1, s] - value["random_walk", 0, s])
            for s in range(3)
        ]
    )
    test = stats.ttest_1samp(contrast, 0.0)
    interval = test.confidence_interval(0.95)
    text = (folder / "compare" / "report.md").read_text(encoding="utf-8")
    first = text.split("\n## ", 2)[1]
    assert first.startswith("Is A more robust than B? (auc_known_at_base against failures)")
    row = [c.strip() for c in first.split("| strategy=frontier |", 1)[1].split("|")]
    assert row[1] == "1 vs 0" and row[2] == "3" and row[3] == "0"
    assert close(row[4], contrast.mean())
    low, high = row[5].strip("[]").split(", ")
    assert close(low, interval.low) and close(high, interval.high)
    assert close(row[6], test.pvalue)
    assert close(row[8], contrast.mean() / contrast.std(ddof=1))
    assert printed.startswith("Is A more robust than B? Contrast of auc_known_at_base")
    assert "A strategy=frontier, B strategy=random_walk, failures 1 vs 0:" in printed
