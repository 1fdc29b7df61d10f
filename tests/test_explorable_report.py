"""``mresim validate --explorable``'s report of where a team can go and what it can see
(output/explorable_report.py): shares per robot size, the team's, and the warnings."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from test_explorable_metrics import narrow_door_map, write_scenario

from mresim_phys.cli import main


def validate(path: Path, capsys: pytest.CaptureFixture[str]) -> tuple[list[str], list[str]]:
    assert main(["validate", "--explorable", str(path)]) == 0
    captured = capsys.readouterr()
    return captured.out.splitlines(), captured.err.splitlines()


def test_validate_gives_each_robot_size_and_the_team_share(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    robots = [
        {"name": "A", "start": [10, 20], "heading_deg": 0},
        {"name": "B", "start": [10, 40], "heading_deg": 0},
        {"name": "S", "start": [20, 30], "radius": 0.5, "sensor": {"range": 200}},
    ]
    out, err = validate(write_scenario(tmp_path, robots=robots), capsys)
    free = np.count_nonzero(~narrow_door_map())
    assert out[1] == f"  free cells: {free:,}; 4-connected to the starts: 100.0 %"
    assert out[2].startswith("  robots of radius 2 and laser range 30 (A, B): reach ")
    assert out[3].startswith("  robots of radius 0.5 and laser range 200 (S): reach 100.0 %")
    assert out[4] == f"  team: explorable 100.0 % of the free cells ({free:,} cells)"
    assert err == []  # the small robot goes everywhere; the big ones meet it


def test_a_robot_that_cannot_meet_the_others_is_warned_about(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    robots = [
        {"name": "A", "start": [10, 20], "heading_deg": 0},
        {"name": "C", "start": [60, 30], "radius": 1.6},  # beyond the door it cannot pass
    ]
    out, err = validate(write_scenario(tmp_path, robots=robots), capsys)
    assert "(C): reach " in out[3]
    assert err == [  # the two are apart: each is warned about
        f"mresim: warning: robot {name} starts in a pocket: no other robot can reach where it"
        " can go"
        for name in ("'A' (radius 2)", "'C' (radius 1.6)")
    ]


def test_a_robot_in_a_closed_room_is_warned_about(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    walled = narrow_door_map()
    walled[28:31, 40:42] = True  # no door
    robots = [{"name": "C", "start": [60, 30], "radius": 1.0}]
    _, err = validate(write_scenario(tmp_path, grid=walled, robots=robots), capsys)
    assert err == [
        "mresim: warning: robot 'C' (radius 1) starts in a pocket: no free path leads from"
        " where it can go to the base station"
    ]


def test_a_robot_that_reaches_little_of_the_map_is_warned_about(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    robots = [{"name": "A", "start": [20, 32], "radius": 12.0, "heading_deg": 0}]
    _, err = validate(write_scenario(tmp_path, robots=robots), capsys)
    assert err == [
        "mresim: warning: robot 'A' (radius 12) can reach only 6.2 % of the free cells"
        " (warned below 25%): narrow passages or its start keep its body out of the rest of"
        " the map"
    ]
