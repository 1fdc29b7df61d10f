"""The figures papers report (``discovery_feature.py``, ``output/team.py``): overlap and
workload balance from each robot's own discoveries, the longest path, time to more coverage
levels, success within a budget; checked on hand-built cases with known answers, and
recomputed on replay."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from mresim_phys import Simulation
from mresim_phys.cli import main
from mresim_phys.columns import value_of
from mresim_phys.discovery_feature import (
    DISCOVERY,
    Discovered,
    Discovery,
    overlap_of,
    workload_cv_of,
)
from mresim_phys.output.team import team_summary

ROOMS = Path(__file__).resolve().parent.parent / "scenarios" / "13_rooms_4_robots.yaml"


def test_overlap_and_workload_of_a_hand_built_case() -> None:
    """A discovers cells 0..9, then B cells 5..14: B's 5..9 are its second discoveries."""
    team = np.zeros((4, 5), dtype=np.uint8)
    a, b = Discovery(team), Discovery(team)
    a.pending = np.arange(0, 10)
    b.pending = np.arange(5, 15)
    a.count()
    b.count()
    values = [
        Discovered(a.discovered, a.first, a.again),
        Discovered(b.discovered, b.first, b.again),
    ]
    assert values == [Discovered(10, 10, 0), Discovered(10, 5, 5)]
    assert overlap_of(values) == pytest.approx(5 / 15)  # cells discovered twice / discovered
    assert workload_cv_of(values) == pytest.approx(np.std([10, 5]) / 7.5)
    c = Discovery(team)
    c.pending = np.arange(5, 8)  # a third robot on cells two had: neither first nor second
    c.count()
    assert (c.first, c.again, int(team.reshape(-1)[5])) == (0, 0, 3)


def test_a_robot_alone_overlaps_nothing_and_carries_the_whole_load(
    scenario_file: Callable[..., Path],
) -> None:
    robots = [{"name": "A", "start": [8, 20], "heading_deg": 0}]
    sim = Simulation.from_yaml(scenario_file(robots=robots, metrics={"team": True}))
    record = sim.run()
    assert value_of("overlap", record) == 0.0 and value_of("workload_cv", record) == 0.0
    assert value_of("longest_path", record) == pytest.approx(sim.robots[0].distance)
    found = DISCOVERY.value_in(sim.robots[0].features)
    assert found is not None and found.first > 0.9 * record.explored * sim.coverage.total


def test_robots_that_cannot_talk_discover_the_same_space(
    scenario_file: Callable[..., Path],
) -> None:
    """Two robots side by side without radios sense the same room: most of their cells
    are discovered twice; with radios they split the work and overlap less."""
    robots = [
        {"name": "A", "start": [8, 20], "heading_deg": 0},
        {"name": "B", "start": [8, 26], "heading_deg": 0},
    ]
    deaf = {"speed": 2, "radius": 1.0, "sensor": {"range": 30}, "comm_range": 0}
    talk = {"speed": 2, "radius": 1.0, "sensor": {"range": 30}, "comm_range": 40}
    alone = Simulation.from_yaml(scenario_file(robots=robots, team=deaf, metrics={"team": True}))
    linked = Simulation.from_yaml(scenario_file(robots=robots, team=talk, metrics={"team": True}))
    apart, together = alone.run(), linked.run()
    assert value_of("overlap", apart) > 0.5  # type: ignore[operator]
    assert value_of("overlap", together) < value_of("overlap", apart)  # type: ignore[operator]


def test_more_levels_and_a_budget(scenario_file: Callable[..., Path]) -> None:
    metrics: dict[str, Any] = {"levels": [0.3, 0.8], "budget": {"explored": 0.8, "within": 40}}
    sim = Simulation.from_yaml(scenario_file(metrics=metrics, steps=80))
    curve = []
    for record in sim.iterate():
        curve.append(record.explored)
    first = next(i for i, v in enumerate(curve) if v >= 0.8)
    assert sim.milestones.explored["0.8"] == first
    assert sim.milestones.explored["0.3"] == next(i for i, v in enumerate(curve) if v >= 0.3)
    assert set(sim.milestones.explored) == {"0.3", "0.5", "0.8", "0.9", "0.95"}
    assert team_summary(sim) == {"success": first <= 40}
    tight = Simulation.from_yaml(
        scenario_file(metrics={"budget": {"explored": 0.8, "within": first - 1}}, steps=80)
    )
    tight.run()
    assert team_summary(tight) == {"success": False}


def test_the_team_columns_and_summary_replay_as_live(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    data = yaml.safe_load(ROOMS.read_text())
    data["map"]["image"] = str((ROOMS.parent / data["map"]["image"]).resolve())
    data["metrics"] = {"team": True}
    path = tmp_path / "rooms.yaml"
    path.write_text(yaml.safe_dump(data))
    out = tmp_path / "run"
    assert (
        main(["run", str(path), "--out", str(out), "--quiet", "--no-plots", "--steps", "80"]) == 0
    )
    header = (out / "metrics.csv").read_text().splitlines()[0].split(",")
    assert {"overlap", "workload_cv", "longest_path", "discovered_A"} <= set(header)
    capsys.readouterr()
    assert main(["replay", str(out), "--metrics"]) == 0
    assert (out / "metrics-replayed.csv").read_bytes() == (out / "metrics.csv").read_bytes()
    printed = capsys.readouterr().out
    assert "team recomputed: identical" in printed and "DIFFERENT" not in printed
    summary = (out / "summary.json").read_text()
    assert '"team"' in summary and '"overlap"' in summary


@pytest.mark.parametrize(
    ("metrics", "field"),
    [
        ({"levels": [1.5]}, "metrics.levels"),
        ({"budget": {"explored": 0.9, "known_at_base": 0.9, "within": 10}}, "exactly one"),
        ({"budget": {"explored": 0.9}}, "metrics.budget.within"),
        ({"team": "perhaps"}, "metrics.team"),
    ],
)
def test_bad_metrics_input_is_one_paragraph_naming_the_field_and_exit_2(
    scenario_file: Callable[..., Path], capsys: pytest.CaptureFixture[str], metrics: Any, field: str
) -> None:
    assert main(["validate", str(scenario_file(metrics=metrics))]) == 2
    err = capsys.readouterr().err
    assert field in err and "Traceback" not in err
