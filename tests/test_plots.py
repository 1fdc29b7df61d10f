"""Plots of one or several runs, from the command line and at the end of a run."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import cv2
import pytest

from mresim_phys.cli import main
from mresim_phys.output.rundata import read_metrics, run_events

pytest.importorskip("matplotlib")
pytest.importorskip("pandas")

FIGURES = ("exploration.png", "distance.png", "links.png")


def test_a_run_draws_its_plots_at_the_end(
    scenario_file: Callable[..., Path], tmp_path: Path
) -> None:
    out = tmp_path / "run"
    assert main(["run", str(scenario_file(steps=10)), "--out", str(out), "--quiet"]) == 0
    for name in FIGURES:
        image = cv2.imread(str(out / "plots" / name))
        assert image is not None and image.shape[0] > 100


def test_plot_command_puts_several_runs_on_one_figure(
    scenario_file: Callable[..., Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    runs = []
    for seed in (1, 2):
        out = tmp_path / f"seed-{seed}"
        flags = ["--seed", str(seed), "--out", str(out), "--quiet", "--no-plots", "--no-log"]
        assert main(["run", str(scenario_file(steps=8)), *flags]) == 0
        runs.append(str(out))
    assert main(["plot", *runs, "--out", str(tmp_path / "figs")]) == 0
    printed = capsys.readouterr().out
    assert all(name in printed for name in FIGURES)
    assert all((tmp_path / "figs" / name).stat().st_size > 1000 for name in FIGURES)


def test_plotting_a_folder_without_metrics_is_a_clear_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["plot", str(tmp_path)]) == 2
    assert "metrics.csv" in capsys.readouterr().err


HEADER = "step,explored,known_at_base,distance,alive,links\n"


@pytest.mark.parametrize(
    ("file", "content", "fragment"),
    [
        pytest.param("metrics.csv", "", "metrics.csv: not a readable CSV", id="empty-metrics"),
        pytest.param("metrics.csv", "hello\nworld\n", "lacks the columns step", id="junk-metrics"),
        pytest.param("metrics.csv", HEADER, "metrics.csv: no rows", id="header-only"),
        pytest.param("metrics.csv", HEADER + "0,a,b,c,d,e\n", "not numbers", id="text-values"),
        pytest.param("metrics.csv", b"\xff\xfe\x00", "metrics.csv: not a readable", id="binary"),
        pytest.param("summary.json", "{junk", "summary.json: not readable JSON", id="junk-summary"),
        pytest.param(
            "summary.json", "[1, 2]", "summary.json: not a JSON object", id="list-summary"
        ),
        pytest.param("log/steps.jsonl", "junk\n", "steps.jsonl: line 1", id="junk-log"),
    ],
)
def test_plotting_a_damaged_run_names_the_file(
    scenario_file: Callable[..., Path],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    file: str,
    content: str | bytes,
    fragment: str,
) -> None:
    out = tmp_path / "run"
    assert (
        main(["run", str(scenario_file(steps=3)), "--out", str(out), "--quiet", "--no-plots"]) == 0
    )
    target = out / file
    target.write_bytes(content) if isinstance(content, bytes) else target.write_text(content)
    capsys.readouterr()
    assert main(["plot", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("mresim: error:") and fragment in err
    assert "Traceback" not in err


EVENTS = [
    {"step": 5, "fail": "B"},
    {"step": 3, "until": 9, "blackout": ["A"]},
]


@pytest.mark.parametrize("log", [True, False], ids=["from the log", "from metrics.csv"])
def test_failures_and_blackouts_are_found_for_the_plots(
    scenario_file: Callable[..., Path], tmp_path: Path, log: bool
) -> None:
    out = tmp_path / "run"
    flags = ["--out", str(out), "--quiet", "--no-plots", *([] if log else ["--no-log"])]
    assert main(["run", str(scenario_file(steps=12, events=EVENTS)), *flags]) == 0
    events = run_events(out, read_metrics(out))
    found = [(e.step, e.kind, e.until) for e in events]
    if log:
        assert found == [(3, "blackout", 9), (5, "failure", None)]
        assert events[1].text == "fail B"
    else:  # a run without a log: only failures, from the robots' states
        assert found == [(5, "failure", None)]
