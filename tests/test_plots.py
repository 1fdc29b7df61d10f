"""Plots of one or several runs, from the command line and at the end of a run."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import cv2
import pytest

from mresim_phys.cli import main

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
