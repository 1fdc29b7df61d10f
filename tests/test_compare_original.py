"""``tools/compare_original.py``: milestones of the original's runs and ours in one denominator."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from conftest import rooms_grid, write_png
from PIL import Image
from tool_modules import load_tool

compare = load_tool("compare_original")
metrics = load_tool("original_metrics")

DRIVER_OUTPUT = """# team=t map=m algo=FrontierExploration seed=1 robots=2 totalFree=1000
cycle wall_ms cpu_ms gui_ms joint base explored known_at_base
1 10.0 10.0 1 100 100 0.1 0.1
2 10.0 10.0 1 500 400 0.5 0.4
3 10.0 10.0 1 899 700 0.899 0.7
java.lang.RuntimeException: a stack trace line the driver printed
4 10.0 10.0 1 950 949 0.95 0.949
# time1(agentSteps)=1 time2(comm)=1 time3(stats)=0 time4(gui)=1 ms
# wall_s=12.5
"""
POSLOG = """cycle robot x y heading goal_x goal_y state
3 A 10 10 0.0 10 10 Initial
3 B 20 10 0.0 20 10 Initial
4 A 20 10 0.0 60 10 Initial
4 B 22 10 0.0 20 40 Initial
5 A 30 10 0.0 60 10 Initial
5 B 22 10 0.0 20 40 Initial
6 A 30 10 0.0 5 5 Initial
6 B 22 10 0.0 5 5 Initial
"""


def curve(explored: list[int], base: list[int], total: int = 100) -> object:
    return metrics.Curve(list(range(len(explored))), explored, base, total)


def test_milestones_are_the_first_step_at_or_past_each_threshold_none_if_never() -> None:
    found = metrics.milestones(curve([10, 50, 89, 90, 94], [0, 10, 20, 95, 95]))
    assert found == {"e50": 1, "e90": 3, "e95": None, "b95": 3}


def test_our_fractions_become_counts_of_the_originals_denominator() -> None:
    # 80 % of our 500 explorable cells are 400 cells: 40 % of the original's 1000 pixels
    cells = metrics.to_original_cells(0.8, 500)
    assert cells == 400
    found = metrics.milestones(metrics.Curve([0, 1], [cells, 1000], [0, 500], 1000))
    assert found["e50"] == 1 and found["b95"] is None


def test_the_censored_median_puts_never_after_every_reached_value() -> None:
    assert metrics.censored_median([30, None, 10]) == 30
    assert metrics.censored_median([1, 2, 3, None]) == 2.5
    assert metrics.censored_median([1, 2, None, None]) is None  # half never: never
    assert metrics.censored_median([]) is None


def test_spread_and_ratio_report_the_count_reached_and_never() -> None:
    assert compare.spread([10, 20, 30]) == "20 (10-30)"
    assert compare.spread([10, None, 30]) == "30 (10-30) [2/3]"
    assert compare.spread([None, None, 30]) == "never (30-30) [1/3]"
    assert compare.spread([None, None]) == "never [0/2]"
    assert compare.spread([]) == "no runs"
    assert compare.ratio([10, 20, 30], [40, 40, 40]) == "0.50"
    assert compare.ratio([None, None, 30], [40, 40, 40]) == "-"


def test_the_originals_wall_pixels_are_band_zero_and_a_small_map_is_centred(
    tmp_path: Path,
) -> None:
    rgba = np.full((4, 6, 4), 255, dtype=np.uint8)
    rgba[0, 0] = (0, 200, 200, 255)  # first band 0: wall, however bright the rest
    rgba[1, 1] = (1, 0, 0, 0)  # dark and transparent but band 0 is 1: free
    Image.fromarray(rgba, "RGBA").save(tmp_path / "small.png")
    walls = metrics.original_obstacles(tmp_path / "small.png")
    assert walls.shape == (600, 800)
    assert walls[298, 397] and np.count_nonzero(walls) == 1  # centred, margin free
    assert metrics.original_total_area(tmp_path / "small.png") == 800 * 600 - 1


def test_the_drivers_output_is_read_as_counts_with_its_total_and_wall_time(
    tmp_path: Path,
) -> None:
    (tmp_path / "run.txt").write_text(DRIVER_OUTPUT)
    found, wall = metrics.read_original_output(tmp_path / "run.txt")
    assert (found.steps, found.explored, found.total) == ([1, 2, 3, 4], [100, 500, 899, 950], 1000)
    assert wall == 12.5
    assert metrics.milestones(found) == {"e50": 2, "e90": 4, "e95": 4, "b95": None}
    (tmp_path / "bad.txt").write_text("hello\n")
    with pytest.raises(metrics.CompareError, match=r"bad\.txt"):
        metrics.read_original_output(tmp_path / "bad.txt")


def test_the_poslog_gives_target_distances_and_slow_steps_while_exploring(
    tmp_path: Path,
) -> None:
    (tmp_path / "pos.txt").write_text(POSLOG)
    tracks = metrics.read_poslog(tmp_path / "pos.txt", home=(5.0, 5.0))
    a, b = tracks
    # A picks (60, 10) at cycle 4 (the first after the random walk), standing at (10, 10)
    # before it: 50 px; the goal home at cycle 6 is the mission's end, not a pick
    assert metrics.goal_pick_distances(a) == [50.0]
    assert metrics.goal_pick_distances(b) == [30.0]  # from (20, 10) to (20, 40)
    assert metrics.slow_steps(a) == (0, 2)  # cycles 4, 5 explore, 10 px each
    assert metrics.slow_steps(b) == (2, 2)  # 2 px, then 0 px
    result = metrics.run_result(metrics.Curve([1], [10], [10], 100), tracks, None)
    assert result.goal_distance == 40.0 and result.slow_exploring == 0.5
    assert result.slow_returning == 1.0  # both stand still at cycle 6, away from home


def write_our_run(run_dir: Path) -> None:
    """A two-step run folder of ours with one robot, 400 explorable cells of 1000."""
    (run_dir / "log").mkdir(parents=True)
    (run_dir / "metrics.csv").write_text(
        "step,explored,known_at_base,distance_A,state_A\n"
        "0,0.5,0.5,0.0,active\n1,1.0,0.75,3.0,active\n2,1.0,1.0,0.0,done\n"
    )
    steps = [
        {"agents": [{"position": [0, 0], "goal": None}, {"position": p, "goal": g}]}
        for p, g in (([10, 10], None), ([13, 10], [40, 50]), ([13, 10], [0, 0]))
    ]
    (run_dir / "log" / "steps.jsonl").write_text("\n".join(json.dumps(s) for s in steps))
    (run_dir / "summary.json").write_text('{"wall_time_s": 2.0}')
    (run_dir / "denominators.json").write_text(
        '{"ours_explorable_cells": 400, "original_total_area": 1000}'
    )


def test_our_run_folder_is_read_in_the_originals_denominator(tmp_path: Path) -> None:
    write_our_run(tmp_path / "run")
    result = metrics.read_ours(tmp_path / "run")
    assert result.final_explored == 0.4 and result.final_base == 0.4
    assert result.milestones == {"e50": None, "e90": None, "e95": None, "b95": None}
    assert result.goal_distance == 50.0  # from (10, 10) to (40, 50)
    assert result.slow_exploring == 1.0  # its one exploring step moved 3 cells
    assert result.slow_returning == 1.0  # done at (13, 10), 13 cells from the base: slow
    assert result.wall_s == 2.0
    (tmp_path / "run" / "denominators.json").write_text("{}")
    with pytest.raises(metrics.CompareError, match="not a complete run"):
        metrics.read_ours(tmp_path / "run")


def original_tree(tmp_path: Path) -> Path:
    """A stand-in for the original's tree: one 800x600 map (the rooms grid in a black
    field) and a greedy team file, plus a recorded run of the original on it."""
    tree = tmp_path / "orig"
    (tree / "environments").mkdir(parents=True)
    (tree / "config").mkdir()
    occupied = np.ones((600, 800), dtype=bool)
    occupied[:60, :80] = rooms_grid()
    write_png(tree / "environments" / "tiny.png", occupied)
    (tree / "config" / "team").write_text(
        "1 BaseStation 8 30 0.0 0 20 1000 BaseStation 1 1\n"
        "2 A 12 20 0.0 30 20 1000 Explorer 1 1\n"
        "3 B 12 45 0.0 30 20 1000 Explorer 1 1\n"
    )
    results = tmp_path / "original-results" / "tiny"
    results.mkdir(parents=True)
    (results / "seed-1.txt").write_text(DRIVER_OUTPUT)
    (results / "seed-1.pos.txt").write_text(POSLOG)
    return tree


def test_the_tool_runs_ours_reads_the_originals_runs_and_writes_the_tables(
    tmp_path: Path,
) -> None:
    tree = original_tree(tmp_path)
    out = tmp_path / "tables.md"
    code = compare.main(
        ["--original", str(tree), "--case", "environments/tiny.png=config/team",
         "--seeds", "1", "--original-seeds", "1", "--steps", "15",
         "--original-results", str(tmp_path / "original-results"),
         "--ours-results", str(tmp_path / "ours"), "--out", str(out)]
    )  # fmt: skip
    assert code == 0
    counts = json.loads((tmp_path / "ours" / "tiny" / "seed-1" / "denominators.json").read_text())
    assert counts["original_total_area"] == np.count_nonzero(~rooms_grid())
    assert counts["pixels_the_wall_rules_disagree_on"] == 0
    assert 0 < counts["ours_explorable_cells"] <= counts["original_total_area"]
    text = out.read_text()
    assert "### tiny" in text and "| steps to 50 % explored | 2 |" in text


def test_a_wrong_original_tree_or_case_is_a_message_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert compare.main(["--original", str(tmp_path)]) == 2
    assert "no environments/ folder" in capsys.readouterr().err
    tree = original_tree(tmp_path)
    assert compare.main(["--original", str(tree), "--case", "environments/tiny.png"]) == 2
    assert "give MAP=TEAM" in capsys.readouterr().err
    assert compare.main(["--original", str(tree), "--case", "environments/tiny.png=nope"]) == 2
    assert "team file 'nope'" in capsys.readouterr().err


def test_set_changes_our_scenarios_and_keeps_those_runs_apart(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--set`` runs ours with a changed field into a folder named by the change: a run
    with other settings is never read as this one's; a wrong value is a message, exit 2."""
    tree = original_tree(tmp_path)
    common = ["--original", str(tree), "--case", "environments/tiny.png=config/team",
              "--seeds", "1", "--original-seeds", "1", "--steps", "15",
              "--original-results", str(tmp_path / "original-results"),
              "--ours-results", str(tmp_path / "ours")]  # fmt: skip
    change = "team.strategy={name: frontier, params: {candidate_power: 2}}"
    assert compare.main([*common, "--set", change]) == 0
    folder = "set team.strategy={name: frontier, params: {candidate_power: 2}}"
    run = tmp_path / "ours" / folder / "tiny" / "seed-1"
    scenario = (run / "scenario.yaml").read_text()
    assert "candidate_power: 2" in scenario
    assert not (tmp_path / "ours" / "tiny").exists()
    wrong = "team.strategy={name: frontier, params: {candidate_power: 9}}"
    assert compare.main([*common, "--set", wrong]) == 2
    assert "candidate_power" in capsys.readouterr().err
    with pytest.raises(SystemExit) as stop:
        compare.main([*common, "--set", "no-equals-sign"])
    assert stop.value.code == 2
    assert "expected PATH=VALUE" in capsys.readouterr().err
