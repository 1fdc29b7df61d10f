"""``mresim import-team``: the original MRESim's team files become scenario YAML."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from conftest import rooms_grid, write_png

from mresim_phys.cli import main
from mresim_phys.sim import Simulation

ROLE_BASED = """1 BaseStation 8 30 0 0 20 1000 BaseStation 1 1
2 Explorer1 30 20 3.14159 30 20 1000 Explorer 3 1
3 Relay1 12 20 0 30 20 1000 Relay 1 2

4 Explorer2 30 45 -1.5708 30 20 1000 Explorer 5 1
5 Relay2 12 45 0 30 20 1000 Relay 1 4
"""
GREEDY = """1 BaseStation 8 30 0 0 20 1000 BaseStation 1 1
2 A 12 20 0 30 20 1000 Explorer 1 1
3 B 12 45 0 30 20 1000 Explorer 1 1
"""


def import_team(tmp_path: Path, text: str) -> tuple[int, Path]:
    (tmp_path / "team.txt").write_text(text)
    write_png(tmp_path / "rooms.png", rooms_grid())
    out = tmp_path / "scenario.yaml"
    code = main(
        ["import-team", str(tmp_path / "team.txt"), "--map", "rooms.png", "--out", str(out)]
    )
    return code, out


def test_a_role_based_team_file_keeps_its_roles_parents_and_poses(tmp_path: Path) -> None:
    code, out = import_team(tmp_path, ROLE_BASED)
    assert code == 0
    sim = Simulation.from_yaml(out)
    robots = {r.name: r for r in sim.robots}
    assert list(robots) == ["Explorer1", "Relay1", "Explorer2", "Relay2"]
    assert (robots["Explorer1"].role, robots["Explorer1"].parent) == ("explorer", "Relay1")
    assert (robots["Relay1"].role, robots["Relay1"].parent) == ("relay", "base")
    assert robots["Relay1"].children == ("Explorer1",)
    assert robots["Explorer1"].position == (30.5, 20.5)  # the centre of pixel (30, 20)
    assert robots["Explorer1"].heading == pytest.approx(3.14159, abs=1e-5)
    assert sim.base.position == (8.5, 30.5) and sim.base.comm_range == 20
    data = yaml.safe_load(out.read_text())
    assert data["team"]["speed"] == 10 and data["robots"][0]["sensor"]["range"] == 30
    assert sim.scenario.communication.model == "path_loss"  # the original's PropModel1


def test_a_greedy_team_file_has_no_hierarchy(tmp_path: Path) -> None:
    code, out = import_team(tmp_path, GREEDY)
    assert code == 0
    assert all(r.parent is None for r in Simulation.from_yaml(out).robots)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("1 BaseStation 8 30 0 0 20 1000 BaseStation 1\n", "line 1: 10 columns"),
        (GREEDY.replace("Explorer 1 1\n3", "Scout 1 1\n3"), "line 2: role 'Scout'"),
        (GREEDY.replace(" 12 20 ", " twelve 20 "), "line 2"),
        (GREEDY.splitlines()[1] + "\n", "must be the base station"),
    ],
)
def test_a_bad_team_file_exits_2_naming_the_line(
    tmp_path: Path, text: str, message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    code, _ = import_team(tmp_path, text)
    err = capsys.readouterr().err
    assert code == 2 and message in err and "Traceback" not in err


def test_the_benchmark_times_a_team_file_as_import_team_reads_it(tmp_path: Path) -> None:
    """``time_team(..., team_file=)``: the original's starts (stacked, as its library
    teams are), headings and PropModel1, with the benchmark's run settings."""
    from mresim_phys.errors import MresimError
    from mresim_phys.output.bench import PRESETS, team_file_scenario, time_team
    from mresim_phys.scenario.load import validate_scenario

    team = tmp_path / "2robots_library"
    team.write_text(
        "1 BaseStation 380 520 0.0 0 200 1000 BaseStation 1 1\n"
        "2 A 390 520 0.0 200 200 1000 Explorer 1 1\n"
        "3 B 390 520 3.14 200 200 1000 Explorer 1 1\n"
    )
    preset = PRESETS["original"]
    data = team_file_scenario(team, preset.map_path, 7, threads=2)
    sim = Simulation(validate_scenario(data))
    assert [r.position for r in sim.robots] == [(390.5, 520.5)] * 2
    assert sim.scenario.communication.model == "path_loss"
    assert (data["steps"], data["stop"]["all_done"], data["simulation"]) == (
        7,
        False,
        {"threads": 2},
    )
    (result,) = time_team(2, preset.map_path, 0, 1, preset, team_file=team)
    assert result.robots == 2 and result.median_ms > 0
    with pytest.raises(MresimError, match="has 2 robots, not 3"):
        time_team(3, preset.map_path, 0, 1, preset, team_file=team)
