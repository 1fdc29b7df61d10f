"""Sweep studies: axes, expansion, checks before running, team sizes, common random numbers."""

from __future__ import annotations

from functools import partial
from pathlib import Path

import pytest
from conftest import write_study

from mresim_phys.cli import main
from mresim_phys.errors import MresimError
from mresim_phys.sim import Simulation
from mresim_phys.sweeps.axes import apply_axis
from mresim_phys.sweeps.expand import expand_runs
from mresim_phys.sweeps.failures import failure_plan
from mresim_phys.sweeps.placement import SPACING
from mresim_phys.sweeps.runner import with_videos
from mresim_phys.sweeps.study import StudyError, load_study
from mresim_phys.world.space import World

REPO = Path(__file__).resolve().parent.parent
QUICKSTART = REPO / "scenarios" / "01_quickstart.yaml"


write_study = partial(write_study, steps=10)  # runs of 10 steps here


def sweep_cli(capsys: pytest.CaptureFixture[str], *args: str | Path) -> tuple[int, str]:
    """``mresim sweep ...`` in-process: (exit code, stderr)."""
    code = main(["sweep", *(str(a) for a in args)])
    return code, capsys.readouterr().err


def test_list_paths_change_every_entry_and_null_drops_them() -> None:
    data = {"faults": {"random": [{"mtbf": 100}, {"probability": 0.1}]}, "team": {"speed": 2}}
    changed = apply_axis(data, "faults.random.after", 50, "s")
    assert [e["after"] for e in changed["faults"]["random"]] == [50, 50]
    assert apply_axis(data, "faults.random.mtbf", None, "s")["faults"]["random"] == []
    assert apply_axis({}, "faults.random.mtbf", 80, "s") == {"faults": {"random": [{"mtbf": 80}]}}
    assert data["faults"]["random"][0] == {"mtbf": 100}  # the base is not changed


def test_team_paths_beat_robot_fields_and_robot_paths_name_robots() -> None:
    data = {"team": {"speed": 2}, "robots": [{"name": "A", "speed": 4}, {"name": "B"}]}
    assert [r["speed"] for r in apply_axis(data, "team.speed", 7, "s")["robots"]] == [7, 7]
    changed = apply_axis(data, "robots.B.speed", 9, "s")["robots"]
    assert [r.get("speed") for r in changed] == [4, 9]
    nulled = apply_axis(data, "team.speed", None, "s")
    assert nulled["team"]["speed"] is None and "speed" not in nulled["robots"][0]


def test_a_path_through_a_number_is_an_error() -> None:
    with pytest.raises(StudyError, match=r"team.speed is 2, not a section"):
        apply_axis({"team": {"speed": 2}}, "team.speed.max", 3, "s")


def test_grid_and_zip_make_their_runs(tmp_path: Path) -> None:
    axes = {"team.strategy": ["frontier", "random_walk"], "team": {"comm_range": [20, 40]}}
    grid = expand_runs(load_study(write_study(tmp_path, axes=axes)), tmp_path / "study.yaml")
    assert len(grid) == 2 * 2 * 2 and len({r.run_id for r in grid}) == 8
    assert grid[0].values == {"team.strategy": "frontier", "team.comm_range": 20}
    assert grid[0].data["seed"] == 0 and grid[1].data["seed"] == 1
    assert grid[0].data["team"]["comm_range"] == 20 and grid[0].data["steps"] == 10
    zipped = expand_runs(load_study(write_study(tmp_path, axes=axes, mode="zip")), tmp_path)
    assert [r.values["team.comm_range"] for r in zipped] == [20, 20, 40, 40]


def test_unknown_path_fails_before_anything_runs(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    study = write_study(tmp_path, axes={"team.comm_rnage": [20, 40]})
    code, err = sweep_cli(capsys, study, "--out", tmp_path / "out", "--workers", "1")
    assert code == 2
    assert "arm 0" in err and "comm_rnage" in err and "did you mean 'comm_range'" in err
    assert "Traceback" not in err and not (tmp_path / "out").exists()


def test_a_value_the_schema_rejects_is_reported_with_its_arm(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    study = write_study(tmp_path, axes={"team.speed": [3, -1]})
    code, err = sweep_cli(capsys, study, "--out", tmp_path / "out")
    assert code == 2 and "arm 1" in err and "team.speed=-1" in err and "team.speed" in err
    assert not (tmp_path / "out").exists()


def test_a_start_inside_a_wall_is_reported_with_its_arm_before_running(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    study = write_study(tmp_path, axes={"robots.A.start": [[66, 52], [0.5, 0.5]]})
    code, err = sweep_cli(capsys, study, "--out", tmp_path / "out")
    assert code == 2 and "arm 1" in err and "inside or overlapping a wall" in err
    assert "Traceback" not in err and not (tmp_path / "out").exists()


def test_bad_study_fields_are_user_errors(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    study = write_study(tmp_path, axes={"team.speed": [3, 4], "team.comm_range": [1]}, mode="zip")
    code, err = sweep_cli(capsys, study)
    assert code == 2 and "zip needs axes of one length" in err
    study = write_study(tmp_path, seed=[1, 2])
    code, err = sweep_cli(capsys, study)
    assert code == 2 and "unknown key 'seed'; did you mean 'seeds'?" in err
    code, err = sweep_cli(capsys, tmp_path / "missing.yaml")
    assert code == 2 and "Study file" in err and "does not exist" in err


def test_an_output_folder_holding_another_study_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    out.mkdir()
    (out / "sweep.json").write_text('{"study": "other", "runs": {}}', encoding="utf-8")
    code, err = sweep_cli(capsys, write_study(tmp_path), "--out", out, "--workers", "1")
    assert code == 2 and "holds a sweep of another study ('other'" in err
    (out / "sweep.json").unlink()
    (out / "notes.txt").write_text("mine", encoding="utf-8")
    code, err = sweep_cli(capsys, write_study(tmp_path), "--out", out, "--workers", "1")
    assert code == 2 and "holds no sweep" in err
    assert (out / "notes.txt").read_text(encoding="utf-8") == "mine"


def test_unreachable_dask_address_is_a_clear_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    study = write_study(tmp_path)
    code, err = sweep_cli(capsys, study, "--out", tmp_path / "out", "--dask", "tcp://127.0.0.1:9")
    assert code == 2 and "no Dask scheduler answered" in err and "Traceback" not in err
    assert not (tmp_path / "out").exists()
    code, err = sweep_cli(capsys, study, "--dask", "local:none")
    assert code == 2 and "expected local:N" in err


def test_team_size_keeps_the_robots_and_places_more_clear_of_walls(tmp_path: Path) -> None:
    study = load_study(write_study(tmp_path, axes={"robots.count": [1, 6]}, seeds=1))
    small, big = expand_runs(study, tmp_path / "study.yaml")
    assert [r["name"] for r in small.data["robots"]] == ["A"]
    robots = big.data["robots"]
    assert [r["name"] for r in robots] == ["A", "B", "R1", "R2", "R3", "R4"]
    scenario = big.load()
    sim = Simulation(scenario)  # every start is free (the build checks it)
    starts = [tuple(r["start"]) for r in robots]
    for i, p in enumerate(starts):
        for q in starts[i + 1 :]:
            assert abs(p[0] - q[0]) >= SPACING or abs(p[1] - q[1]) >= SPACING or i < 2
    world = World(sim.world.occupied.copy(), [])
    assert not any(world.overlaps_wall(p, 2.0) for p in starts[2:])


def test_too_many_failures_for_the_team_is_an_error(tmp_path: Path) -> None:
    study = load_study(write_study(tmp_path, axes={"failures": [0, 3]}))
    with pytest.raises(MresimError, match="3 failures asked for a team of 2 robots"):
        expand_runs(study, tmp_path / "study.yaml")


def test_arms_with_one_seed_share_failures_starts_and_fault_clocks(tmp_path: Path) -> None:
    """Common random numbers: only the strategy differs between the arms of a seed."""
    axes = {"team.strategy": ["frontier", "random_walk"], "failures": [1, 2]}
    study = load_study(
        write_study(tmp_path, axes=axes, seeds=3, steps=200, overrides={"faults.random.mtbf": 90})
    )
    runs = expand_runs(study, tmp_path / "study.yaml")
    by_key = {(r.values["team.strategy"], r.values["failures"], r.seed): r for r in runs}
    for seed in range(3):
        for k in (1, 2):
            a, b = by_key["frontier", k, seed], by_key["random_walk", k, seed]
            assert a.data["events"] == b.data["events"] and len(a.data["events"]) == k
            starts = [[(r["name"], r["start"]) for r in x.data["robots"]] for x in (a, b)]
            assert starts[0] == starts[1] and a.data["map"] == b.data["map"]
            clocks = [
                [c.next_fail for c in Simulation(r.load()).setup.faults.clocks] for r in (a, b)
            ]
            assert clocks[0] == clocks[1]
        one, two = by_key["frontier", 1, seed], by_key["frontier", 2, seed]
        assert one.data["events"][0] in two.data["events"]  # k robots fail also with k + 1
    plans = {tuple(failure_plan(["A", "B"], s, 200, (0.05, 0.35))) for s in range(6)}
    assert len(plans) > 1  # the seed decides
    assert all(10 <= step <= 70 for plan in plans for _, step in plan)


def test_video_for_selects_runs_and_rejects_code(tmp_path: Path) -> None:
    study = load_study(write_study(tmp_path, axes={"team.strategy": ["frontier", "random_walk"]}))
    runs = expand_runs(study, tmp_path / "study.yaml")
    chosen = with_videos(runs, "seed < 1 and strategy == 'frontier'", tmp_path)
    assert [r.run_id for r in chosen if r.video] == ["a000-s0000"]
    with pytest.raises(MresimError, match="Call is not allowed"):
        with_videos(runs, "__import__('os')", tmp_path)
    with pytest.raises(MresimError, match="unknown name 'sed'"):
        with_videos(runs, "sed < 1", tmp_path)


@pytest.mark.parametrize("study_file", sorted((REPO / "studies").glob("*.yaml")))
def test_shipped_studies_are_valid(study_file: Path) -> None:
    runs = expand_runs(load_study(study_file), study_file)
    assert len(runs) >= 160 and len({r.run_id for r in runs}) == len(runs)
    assert all(r.data["render"] == {"plots": False, "video": False} for r in runs[:3])
