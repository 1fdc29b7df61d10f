"""Study files are untrusted input: each mistake is refused with a message naming the file
and the field (exit 2) before anything is built or written.

A ``name`` that would leave ``sweeps/``, booleans and quoted numbers where numbers go, a
study of more runs than a sweep may hold (counted from the axes alone, in well under a
second), values that would run the same arm twice, a reference that is no arm.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import pytest
import yaml

from mresim_phys.cli import main
from mresim_phys.sweeps import expand
from mresim_phys.sweeps.expand import expand_runs
from mresim_phys.sweeps.study import MAX_RUNS, load_study

REPO = Path(__file__).resolve().parent.parent
QUICKSTART = REPO / "scenarios" / "01_quickstart.yaml"


def write_study(folder: Path, **fields: Any) -> Path:
    """A study of the quickstart scenario with ``fields`` (None deletes a field)."""
    data = {"name": "t", "scenarios": [str(QUICKSTART)], "seeds": 2, "steps": 10, **fields}
    path = folder / "study.yaml"
    text = yaml.safe_dump({k: v for k, v in data.items() if v is not None}, sort_keys=False)
    path.write_text(text, encoding="utf-8")
    return path


def sweep(capsys: pytest.CaptureFixture[str], *args: str | Path) -> tuple[int, str]:
    """``mresim sweep ...`` in-process: (exit code, stderr)."""
    capsys.readouterr()
    code = main(["sweep", *(str(a) for a in args)])
    return code, capsys.readouterr().err


def refused(err: str, path: Path, *fragments: str) -> bool:
    """One message naming the file and every fragment, no traceback."""
    named = err.startswith(f"mresim: error: {path}")
    return named and all(f in err for f in fragments) and "Traceback" not in err


# --- the name cannot leave the sweeps folder --------------------------------------------


@pytest.mark.parametrize("name", ["../../escaped", "/tmp/escaped", "a/b", "..", ".", "", "a" * 65])
def test_a_name_that_leaves_the_sweeps_folder_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch, name: str
) -> None:
    work = tmp_path / "deep" / "work"
    work.mkdir(parents=True)
    monkeypatch.chdir(work)
    path = write_study(work, name=name)
    code, err = sweep(capsys, path, "--workers", "1")  # no --out: sweeps/<name>
    assert code == 2 and refused(err, path, "name: a name is made of"), err
    assert sorted(p.name for p in tmp_path.rglob("*")) == ["deep", "study.yaml", "work"]


def test_the_study_name_follows_the_scenario_name_rule() -> None:
    from mresim_phys.scenario.schema import Scenario
    from mresim_phys.sweeps.study import Study

    assert Study.model_fields["name"].metadata == Scenario.model_fields["name"].metadata


# --- counted before anything is built ----------------------------------------------------

HUGE: list[Any] = [
    pytest.param({"seeds": 10**9}, "1000000000 runs", id="a-billion-seeds"),
    pytest.param(
        {
            "axes": {
                "team.speed": list(range(1, 51)),
                "team.comm_range": list(range(1, 51)),
                "team.radius": [x / 10 for x in range(1, 51)],
            },
            "seeds": 1,
        },
        "125000 runs",
        id="125000-arms",
    ),
    pytest.param(
        {"axes": {f"robots.A.p{i}": list(range(10)) for i in range(20)}, "seeds": 1},
        f"{10**20} runs",
        id="10^20-arms",
    ),
    pytest.param(
        {"scenarios": [str(QUICKSTART), "b.yaml"], "seeds": MAX_RUNS // 2 + 1},
        f"{MAX_RUNS + 2} runs",
        id="scenarios-times-seeds",
    ),
    pytest.param(
        {"mode": "zip", "axes": {"team.speed": list(range(1, 1001))}, "seeds": 101},
        "101000 runs",
        id="zip",
    ),
]


@pytest.mark.parametrize(("fields", "count"), HUGE)
def test_too_many_runs_are_refused_at_once_from_the_axes_alone(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    fields: dict[str, Any],
    count: str,
) -> None:
    def no_arm(*args: Any) -> None:
        raise AssertionError("an arm was built before the runs were counted")

    monkeypatch.setattr(expand, "make_arm", no_arm)
    path = write_study(tmp_path, **fields)
    started = time.perf_counter()
    code, err = sweep(capsys, path, "--out", tmp_path / "out", "--workers", "1")
    elapsed = time.perf_counter() - started
    assert code == 2 and refused(err, path, "scenarios x axes x seeds", count), err
    assert f"more than the {MAX_RUNS}" in err and elapsed < 0.5, elapsed
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    "fields",
    [
        {"axes": {"team.speed": [2, 3], "team.comm_range": [20, 30, 40]}, "seeds": [0, 5]},
        {"mode": "zip", "axes": {"team.speed": [2, 3], "team.comm_range": [20, 30]}, "seeds": 3},
        {"scenarios": [str(QUICKSTART), str(REPO / "scenarios/02_office_frontier.yaml")]},
    ],
)
def test_the_count_is_the_number_of_runs_made(tmp_path: Path, fields: dict[str, Any]) -> None:
    path = write_study(tmp_path, **fields)
    study = load_study(path)
    assert study.run_count == len(expand_runs(study, path))


# --- numbers are numbers --------------------------------------------------------------------

NOT_NUMBERS: list[Any] = [
    pytest.param({"axes": {"failures": [True]}}, "axes.failures", id="failures-true"),
    pytest.param({"axes": {"failures": [0, False]}}, "axes.failures", id="failures-false"),
    pytest.param({"axes": {"failures": ["1"]}}, "axes.failures", id="failures-text"),
    pytest.param({"axes": {"failures": [1.0]}}, "axes.failures", id="failures-float"),
    pytest.param({"seeds": "20"}, "seeds", id="seeds-text"),
    pytest.param({"seeds": True}, "seeds", id="seeds-true"),
    pytest.param({"seeds": [0, "1"]}, "seeds", id="seeds-list-text"),
    pytest.param({"seeds": [False, 1]}, "seeds", id="seeds-list-bool"),
    pytest.param({"seeds": 2.5}, "seeds", id="seeds-fraction"),
    pytest.param({"steps": "10"}, "steps", id="steps-text"),
    pytest.param({"steps": True}, "steps", id="steps-true"),
    pytest.param({"failure_window": ["0.1", 0.3]}, "failure_window", id="window-text"),
    pytest.param({"failure_window": [True, 0.3]}, "failure_window", id="window-true"),
]


@pytest.mark.parametrize(("fields", "field"), NOT_NUMBERS)
def test_booleans_and_quoted_numbers_are_refused_naming_the_field(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], fields: dict[str, Any], field: str
) -> None:
    path = write_study(tmp_path, **fields)
    code, err = sweep(capsys, path, "--out", tmp_path / "out")
    assert code == 2 and refused(err, path, f"  - {field}"), err
    assert len(err.strip().splitlines()) == 2  # the file, one problem


# --- no arm twice, a reference that is an arm ------------------------------------------------

SAME_ARMS: list[Any] = [
    pytest.param({"axes": {"team.strategy": ["frontier", "frontier"]}}, "axes.team.strategy"),
    pytest.param({"axes": {"robots": {"count": [2, 4, 2]}}}, "axes.robots.count"),
    pytest.param(
        {"mode": "zip", "axes": {"team.speed": [2, 3, 2], "team.comm_range": [20, 30, 20]}},
        "the combination {'team.speed': 2, 'team.comm_range': 20} comes more than once",
    ),
    pytest.param({"scenarios": [str(QUICKSTART)] * 2}, "scenarios: ["),
    pytest.param({"seeds": [0, 1, 0]}, "seeds: the seeds repeat: [0]"),
    pytest.param({"reference": {"team.stratgy": "frontier"}}, "did you mean 'team.strategy'?"),
    pytest.param({"reference": {"team.strategy": "hungarian"}}, "not one of the axis's values"),
]


@pytest.mark.parametrize(("fields", "fragment"), SAME_ARMS)
def test_the_same_arm_twice_or_a_reference_to_no_arm_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], fields: dict[str, Any], fragment: str
) -> None:
    fields = {"axes": {"team.strategy": ["frontier", "random_walk"]}, **fields}
    path = write_study(tmp_path, **fields)
    code, err = sweep(capsys, path, "--out", tmp_path / "out")
    assert code == 2 and refused(err, path, fragment), err


def test_zip_may_repeat_a_value_in_different_combinations(tmp_path: Path) -> None:
    axes = {"team.strategy": ["frontier", "frontier"], "team.speed": [2, 3]}
    path = write_study(tmp_path, axes=axes, mode="zip", reference={"team.speed": 3})
    assert load_study(path).run_count == 4


@pytest.mark.parametrize(
    ("flags", "fragment"),
    [
        (["--strategies", "frontier,frontier"], "--strategies gives frontier more than once"),
        (["--strategies", "frontier,random_walk,frontier"], "--strategies gives frontier"),
        (["--failures", "0,1,1"], "--failures gives 1 more than once"),
    ],
)
def test_robustness_refuses_a_strategy_or_count_given_twice(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], flags: list[str], fragment: str
) -> None:
    capsys.readouterr()
    out = tmp_path / "out"
    code = main(["robustness", str(QUICKSTART), *flags, "--seeds", "1", "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and err.startswith(f"mresim: error: mresim robustness {QUICKSTART}"), err
    assert fragment in err and not out.exists()


def test_robustness_names_its_study_within_the_name_rule(tmp_path: Path) -> None:
    from mresim_phys.sweeps.robustness import robustness_study

    data = yaml.safe_load(QUICKSTART.read_text(encoding="utf-8"))
    data["map"]["image"] = str(REPO / "maps" / "small_rooms.png")
    for name, expected in [("q" * 64, "q" * 53 + "-robustness"), ("../x", "scenario-robustness")]:
        path = tmp_path / "scenario.yaml"
        path.write_text(yaml.safe_dump({**data, "name": name}), encoding="utf-8")
        study, _ = robustness_study(path, ["frontier"], [0, 1], 2)
        assert study["name"] == expected


# --- what the study reads --------------------------------------------------------------------


def bomb(levels: int = 9) -> str:
    """A flow list whose aliases expand to 10 ** (levels + 1) values."""
    parts = ["&a0 [x, x, x, x, x, x, x, x, x, x]"]
    parts += [f"&a{i} [{', '.join([f'*a{i - 1}'] * 10)}]" for i in range(1, levels + 1)]
    return f"[{', '.join(parts)}]"


@pytest.mark.parametrize(
    "place", ["axes: {team.speed: BOMB}", "overrides: {x: BOMB}", "seeds: BOMB"]
)
def test_an_alias_bomb_in_a_study_is_refused_at_once(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], place: str
) -> None:
    lines = {"name": "name: bomb", "scenarios": f"scenarios: [{QUICKSTART}]", "seeds": "seeds: 1"}
    lines[place.split(":")[0]] = place.replace("BOMB", bomb())
    path = tmp_path / "study.yaml"
    path.write_text("\n".join(lines.values()) + "\n", encoding="utf-8")
    started = time.perf_counter()
    code, err = sweep(capsys, path, "--out", tmp_path / "out")
    assert code == 2 and err.startswith(f"mresim: error: Study file {path}"), err
    assert "aliases" in err and time.perf_counter() - started < 2.0
    assert not (tmp_path / "out").exists()


def test_a_study_override_does_not_hide_a_base_scenarios_own_wrong_value(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    base = yaml.safe_load(QUICKSTART.read_text(encoding="utf-8"))
    base["map"]["image"] = str(REPO / "maps" / "small_rooms.png")
    scenario = tmp_path / "base.yaml"
    scenario.write_text(yaml.safe_dump({**base, "steps": -5}), encoding="utf-8")
    path = write_study(tmp_path, scenarios=["base.yaml"], steps=10)  # the study caps steps
    code, err = sweep(capsys, path, "--out", tmp_path / "out")
    assert code == 2 and refused(err, path, "scenarios:", f"{scenario}", "steps"), err


def test_an_override_that_runs_into_a_number_names_the_study_and_overrides(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = write_study(tmp_path, overrides={"team.speed.max": 3})
    code, err = sweep(capsys, path, "--out", tmp_path / "out")
    assert code == 2 and refused(err, path, "overrides:", "team.speed is 3, not a section"), err


AXIS_MISTAKES: list[Any] = [
    pytest.param({"robots.A.strategy": [None, "random_walk"]}, "robots[0].strategy", id="null"),
    pytest.param({"robots.Z.speed": [None]}, "names robot 'Z'", id="null-unknown-robot"),
    pytest.param(
        {"team.strategy.params": [None]}, "team.strategy is 'frontier', not a section", id="text"
    ),
    pytest.param({"robots.count": [10**9]}, "room for at most", id="a-billion-robots"),
]


@pytest.mark.parametrize(("axes", "fragment"), AXIS_MISTAKES)
def test_an_axis_that_cannot_apply_is_refused_with_its_arm_at_once(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], axes: dict[str, Any], fragment: str
) -> None:
    path = write_study(tmp_path, axes=axes)
    started = time.perf_counter()
    code, err = sweep(capsys, path, "--out", tmp_path / "out")
    assert code == 2 and refused(err, path, "arm 0", fragment), err
    assert time.perf_counter() - started < 2.0
