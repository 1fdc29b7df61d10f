"""Every YAML the project reads is bounded: alias bombs, alias loops, huge files and
devices are refused at once with a message naming the file, before any value is built."""

from __future__ import annotations

import os
import time
from pathlib import Path

import pytest

from mresim_phys.errors import MapError, ScenarioError
from mresim_phys.scenario import yamlfile
from mresim_phys.scenario.readers import load_ros_map, read_yaml_mapping
from mresim_phys.scenario.yamlfile import MAX_ALIAS_VALUES, YamlSizeError, parse_yaml


def alias_bomb(levels: int = 9, fan: int = 10, key: str = "robots") -> str:
    """A 'billion laughs' document: ``fan ** levels`` leaves through aliases."""
    lines = ["name: bomb", "seed: 1", "steps: 3", "l0: &l0 [{name: a, start: [1, 1]}]"]
    for i in range(1, levels):
        lines.append(f"l{i}: &l{i} [" + ", ".join([f"*l{i - 1}"] * fan) + "]")
    lines.append(f"{key}: *l{levels - 1}")
    return "\n".join(lines) + "\n"


def test_an_alias_bomb_is_refused_before_it_is_built(tmp_path: Path) -> None:
    path = tmp_path / "bomb.yaml"
    path.write_text(alias_bomb(), encoding="utf-8")
    assert path.stat().st_size < 2000
    started = time.perf_counter()
    with pytest.raises(ScenarioError, match=r"bomb\.yaml.*aliases .*over the limit"):
        read_yaml_mapping(path)
    assert time.perf_counter() - started < 2.0


def test_an_alias_bomb_in_a_ros_map_file_is_a_map_error(tmp_path: Path) -> None:
    path = tmp_path / "map.yaml"
    path.write_text(alias_bomb(key="origin"), encoding="utf-8")
    with pytest.raises(MapError, match=r"ROS map file .*map\.yaml.*alias bomb"):
        load_ros_map(path)


def test_aliases_within_the_bound_read_as_plain_yaml() -> None:
    text = "team: &t {speed: 3, radius: 2}\nrobots:\n" + "".join(
        f"  - {{name: r{i}, <<: *t}}\n" for i in range(50)
    )
    data = parse_yaml(text)
    assert len(data["robots"]) == 50
    assert data["robots"][49] == {"name": "r49", "speed": 3, "radius": 2}


def test_the_bound_counts_values_added_by_aliases_not_values_written() -> None:
    """A long list written out is fine; the same count reached through aliases is not."""
    written = "xs: [" + ", ".join(["1"] * (MAX_ALIAS_VALUES + 10)) + "]\n"
    assert len(parse_yaml(written)["xs"]) == MAX_ALIAS_VALUES + 10
    fan = 1000
    aliased = "a: &a [" + ", ".join(["1"] * fan) + "]\nb: [" + ", ".join(["*a"] * 101) + "]\n"
    with pytest.raises(YamlSizeError):
        parse_yaml(aliased)
    within = "a: &a [" + ", ".join(["1"] * fan) + "]\nb: [" + ", ".join(["*a"] * 99) + "]\n"
    assert len(parse_yaml(within)["b"]) == 99


@pytest.mark.parametrize(
    "text", ["a: &a [1, *a]\n", "a: &a {k: *a}\n", "a: &a [[[*a]]]\n", "&a [*a]\n"]
)
def test_an_alias_inside_its_own_value_is_refused(text: str) -> None:
    with pytest.raises(YamlSizeError, match="loop"):
        parse_yaml(text)


def test_a_device_or_a_pipe_is_not_read(tmp_path: Path) -> None:
    with pytest.raises(ScenarioError, match="not a regular file"):
        read_yaml_mapping(Path("/dev/zero"))
    fifo = tmp_path / "pipe.yaml"

    os.mkfifo(fifo)
    with pytest.raises(ScenarioError, match="not a regular file"):
        read_yaml_mapping(fifo)  # would block forever if opened


def test_a_file_over_the_size_limit_is_refused_unread(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(yamlfile, "MAX_YAML_BYTES", 1000)
    path = tmp_path / "big.yaml"
    path.write_text("name: big\n" + "# padding\n" * 200, encoding="utf-8")
    with pytest.raises(ScenarioError, match=r"big\.yaml is 2,010 bytes, over the limit"):
        read_yaml_mapping(path)


def test_mresim_validate_refuses_an_alias_bomb_with_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from mresim_phys.cli import main

    path = tmp_path / "bomb.yaml"
    path.write_text(alias_bomb(), encoding="utf-8")
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err
    assert "bomb.yaml" in err and "Traceback" not in err
