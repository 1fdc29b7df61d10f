"""``mresim warmup`` (``output/warmup.py``): its profiles are valid scenarios on the package's
own maps, a bad profile name or a failing profile is said, and the README's first command
warms the kernels (tools/check_wheel.sh checks, from an installed wheel, that the quickstart
then compiles none)."""

from __future__ import annotations

import argparse
import shutil
from pathlib import Path

import pytest

from mresim_phys.cli import main
from mresim_phys.output import warmup
from mresim_phys.scenario.load import load_scenario


def test_every_profile_is_a_valid_scenario_on_packaged_maps() -> None:
    found = warmup.profiles()
    assert next(iter(found)) == warmup.CORE and len(found) >= 7
    for name, path in found.items():
        scenario = load_scenario(path)
        assert Path(scenario.map.image).resolve().is_relative_to(warmup.profile_folder().parent)
        assert not scenario.render.video and not scenario.render.plots, name


def test_list_names_every_profile(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["warmup", "--list"]) == 0
    listed = [line.split()[0] for line in capsys.readouterr().out.splitlines()]
    assert listed == list(warmup.profiles())


def test_an_unknown_profile_is_a_user_error(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["warmup", "--profiles", "core,lidar"]) == 2
    err = capsys.readouterr().err
    assert "lidar" in err and "radio" in err and "Traceback" not in err


def test_a_failing_profile_is_reported(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = tmp_path / "warmup"
    folder.mkdir()
    shutil.copy(warmup.profiles()["core"], folder / "core.yaml")  # its map is not beside it
    monkeypatch.setattr(warmup, "profile_folder", lambda: folder)
    args = argparse.Namespace(list=False, profiles=None, workers=1)
    assert warmup.warmup_command(args) == 1
    err = capsys.readouterr().err
    assert "core (exit 2)" in err and "small_rooms.png" in err
