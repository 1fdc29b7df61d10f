"""Tests for the corpus of real building maps (maps/corpus) and its runner (tools/corpus.py)."""

from __future__ import annotations

import csv
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest
import yaml
from tool_modules import load_tool

from mresim_phys.scenario.load import load_scenario
from mresim_phys.scenario.readers import load_ros_map

corpus: ModuleType = load_tool("corpus")
corpus_report: ModuleType = load_tool("corpus_report")  # loaded by corpus
MAPS = corpus.load_index()
NAMES = [m.name for m in MAPS]


def test_index_lists_at_least_eight_maps_of_varied_kinds() -> None:
    kinds = {m.kind for m in MAPS}
    assert len(MAPS) >= 8
    assert len(set(NAMES)) == len(NAMES)
    assert {"office", "warehouse"} <= kinds
    assert kinds & {"hospital", "hotel"}


def test_index_entries_name_their_files_source_and_licence() -> None:
    raw = yaml.safe_load(corpus.INDEX.read_text(encoding="utf-8"))["maps"]
    for entry, m in zip(raw, MAPS, strict=True):
        meta = yaml.safe_load(m.file.read_text(encoding="utf-8"))
        image = m.file.parent / meta["image"]
        assert image.is_file(), image
        assert image.stat().st_size < 400_000, f"{image} is not small"
        assert m.licence.strip(), m.name
        assert m.source.startswith("https://github.com/"), m.name
        assert isinstance(entry["modified"], bool)
        assert entry["changes"] or not entry["modified"], f"{m.name}: modified but no change"
        assert meta["resolution"] == pytest.approx(m.resolution)
        assert len(m.starts) == 8


def test_an_entry_without_a_licence_is_refused(tmp_path: Path) -> None:
    raw = yaml.safe_load(corpus.INDEX.read_text(encoding="utf-8"))
    raw["maps"][0]["licence"] = ""
    index = tmp_path / "corpus.yaml"
    index.write_text(yaml.safe_dump(raw), encoding="utf-8")
    with pytest.raises(ValueError, match=f"{NAMES[0]}.*licence"):
        corpus.load_index(index)


@pytest.mark.parametrize("entry", MAPS, ids=NAMES)
def test_map_loads_and_its_starts_are_free_clear_and_connected(entry: Any) -> None:
    loaded = load_ros_map(entry.file)
    rows, cols = loaded.occupied.shape
    assert rows * cols <= 700_000
    assert loaded.resolution == pytest.approx(entry.resolution)
    for x, y in [entry.base, *entry.starts]:
        assert not loaded.occupied[y, x]
    assert corpus.check_map(entry) == []


def test_check_map_reports_a_start_on_a_wall() -> None:
    entry = MAPS[0]
    occupied = load_ros_map(entry.file).occupied
    wall = next(
        (c, r) for r in range(occupied.shape[0]) for c in range(occupied.shape[1]) if occupied[r, c]
    )
    moved = type(entry)(**{**entry.__dict__, "starts": (wall, *entry.starts[1:])})
    assert any("from a wall" in p for p in corpus.check_map(moved))


def test_select_names_maps_and_refuses_unknown_ones() -> None:
    assert [m.name for m in corpus.select(MAPS, f"{NAMES[1]},{NAMES[0]}")] == NAMES[1::-1]
    assert corpus.select(MAPS, "all") == MAPS
    with pytest.raises(ValueError, match="nowhere"):
        corpus.select(MAPS, "nowhere")


@pytest.mark.parametrize("strategy", corpus.STRATEGIES)
def test_scenarios_validate_and_pair_role_based_teams(strategy: str, tmp_path: Path) -> None:
    job = corpus.Job(MAPS[0], strategy, 5, 3, 50, (0.5, 1.0))
    path = tmp_path / "s.yaml"
    path.write_text(yaml.safe_dump(corpus.scenario_data(job)), encoding="utf-8")
    scenario = load_scenario(path)
    assert scenario.seed == 3
    assert scenario.steps == 50
    assert [r.radius for r in scenario.robots] == [0.5, 1.0, 0.5, 1.0, 0.5]
    assert scenario.robots[0].sensor.range == round(8.0 / MAPS[0].resolution)
    roles = [(r.role, r.parent) for r in scenario.robots]
    if strategy == "role_based":
        relay = ("relay", "base")
        assert roles == [relay, ("explorer", "R1"), relay, ("explorer", "R3"), ("explorer", None)]
    else:
        assert {role for role, _ in roles} == {"explorer"}


def test_a_team_bigger_than_the_starts_is_refused() -> None:
    with pytest.raises(ValueError, match="fewer starts"):
        corpus.make_jobs(MAPS[:1], ["frontier"], [9], [1], 10)


def fake_summary(explored: float, reached: int | None) -> dict[str, Any]:
    return {
        "steps": 40,
        "stop_reason": "steps",
        "final_explored": explored,
        "final_known_at_base": explored / 2,
        "steps_to_explored": {"0.5": reached, "0.9": None, "0.95": None},
        "steps_to_known_at_base": {"0.5": None, "0.9": None, "0.95": None},
        "robots": {"A": {"state": "active"}, "B": {"state": "error"}},
        "alive": 2,
        "health": {"robots_fruitless": 1, "fruitless_robot_steps": 100 + reached if reached else 0},
    }


def test_rows_and_report_give_medians_and_robot_states(tmp_path: Path) -> None:
    job = corpus.Job(MAPS[0], "frontier", 2, 1, 40)
    rows = [
        {**corpus.job_fields(job), **corpus.summary_fields(fake_summary(e, r))}
        for e, r in ((0.6, 20), (0.8, None), (0.7, 30))
    ]
    assert rows[0]["robot_states"] == "A:active B:error"
    assert (rows[0]["robots_active"], rows[0]["robots_error"]) == (1, 1)
    corpus.write_csv(rows, tmp_path / "c.csv")
    with (tmp_path / "c.csv").open(encoding="utf-8") as handle:
        read = list(csv.DictReader(handle))
    assert [r["final_explored"] for r in read] == ["0.6", "0.8", "0.7"]
    table = corpus.report(rows)
    line = next(t for t in table.splitlines() if t.startswith("| frontier | 2 |"))
    cells = [c.strip() for c in line.strip("|").split("|")]
    assert cells[2:6] == ["3", "0.7", "0.35", "25 (2/3)"]
    assert cells[-2:] == ["active 3, error 3", "120"]  # fruitless robot-steps: 120, 0, 130


def test_every_robot_counts_relays_too() -> None:
    health = {
        "R1": {"idle_with_frontier": 90},  # a relay that idled (waiting is not counted)
        "R2": {"idle_with_frontier": 12},
        "R3": {"idle_with_frontier": 3},
    }
    fields = corpus.idle_fields({"health": {"robots": health}})
    assert fields == {"robot_idle_with_frontier": 90, "idlest_robot": "R1"}
    assert corpus.idle_fields({}) == {"robot_idle_with_frontier": 0, "idlest_robot": ""}
    none = {"health": {"robots": {"R1": {"idle_with_frontier": 0}}}}
    assert corpus.idle_fields(none) == {"robot_idle_with_frontier": 0, "idlest_robot": ""}


def test_violations_name_what_breaks_the_invariant() -> None:
    bound = corpus_report.IDLE_BOUND
    row = {"error": "", "final_explored": 0.97, "steps": 300, "strategy": "frontier",
           "robot_idle_with_frontier": bound, "idlest_robot": "R2"}  # fmt: skip
    assert corpus_report.violations(row) == []
    row |= {"final_explored": 0.9, "robot_idle_with_frontier": bound + 1}
    assert corpus_report.violations(row) == [
        "explored 0.9 after 300 steps",
        f"R2 idled {bound + 1} steps with reachable frontier cells",
    ]
    assert corpus_report.violations({**row, "error": "ValueError: x"}) == ["failed: ValueError: x"]
    relay = {**row, "final_explored": 0.97, "strategy": "role_based"}
    assert corpus_report.violations(relay) == [
        f"R2 idled {bound + 1} steps with reachable frontier cells"
    ]


def test_a_run_that_fails_breaks_the_invariant_with_its_error(tmp_path: Path) -> None:
    gone = type(MAPS[0])(**{**MAPS[0].__dict__, "file": tmp_path / "gone.yaml"})
    row = corpus.run_job(corpus.Job(gone, "frontier", 2, 1, 5), tmp_path / "out")
    assert row["error"] and row["invariant"] == f"failed: {row['error']}"
    assert "break the invariant (1 of 1)" in corpus.report([row])


# Runs of the slow matrix that stop for a documented reason short of the invariant's 95 %:
# (map, strategy, size, seed) -> why. Such a run must end `stalled` and break the invariant
# by its explored share alone; a listed run that holds the invariant fails the test too.
SLIVERS = (
    "SLAM laser fans: free wedges seen only along their axis; the team creeps on them by"
    " less than 0.1 % in 300 steps and the run stops stalled short of 95 % (docs/real-maps.md)"
)
KNOWN: dict[tuple[str, str, int, int], str] = {
    ("ipa_office", "frontier", 3, 1): SLIVERS,
    ("ipa_office", "role_based", 6, 1): SLIVERS,
    ("ipa_office", "utility_return", 6, 1): SLIVERS,
    ("ipa_office", "role_based", 6, 2): SLIVERS,
}
INVARIANT_SIZES = [3, 6]
INVARIANT_SEEDS = [1, 2]
INVARIANT_STEPS = 1500  # a cap: a run stops when the base knows 95 % of the explorable area


@pytest.mark.slow
def test_the_invariant_holds_on_every_map(tmp_path: Path) -> None:
    jobs = corpus.make_jobs(
        MAPS, corpus.STRATEGIES, INVARIANT_SIZES, INVARIANT_SEEDS, INVARIANT_STEPS, (0.5, 1.0)
    )
    rows = corpus.run_all(jobs, tmp_path, workers=2)
    assert (
        len(rows)
        == len(jobs)
        == len(MAPS) * len(corpus.STRATEGIES) * len(INVARIANT_SIZES) * len(INVARIANT_SEEDS)
    )
    broken = {
        (r["map"], r["strategy"], int(r["size"]), int(r["seed"])): r for r in rows if r["invariant"]
    }
    assert {k: r["invariant"] for k, r in broken.items() if k not in KNOWN} == {}
    assert sorted(set(KNOWN) - set(broken)) == []
    for row in broken.values():  # the documented reason: stalled short of 95 % explored
        assert row["stop_reason"] == "stalled"
        assert row["invariant"].startswith("explored ") and "idled" not in row["invariant"]


def test_the_command_line_refuses_unknown_maps_and_strategies(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert corpus.main(["run", "--maps", "nowhere", "--out", str(tmp_path)]) == 2
    assert corpus.main(["run", "--strategies", "frontierr", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "unknown corpus maps ['nowhere']" in err
    assert "unknown strategies ['frontierr']" in err
    assert not (tmp_path / "corpus.csv").exists()
