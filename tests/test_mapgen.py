"""Procedural maps (``mapgen/``, ``mresim make-map``): every kind is one connected space, its
base and starts are free and reachable, the same seed gives the same map in any process,
its scenario runs, and bad requests are one paragraph naming the parameter, exit 2."""

from __future__ import annotations

import subprocess
import sys
from contextlib import nullcontext
from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import ndimage

from mresim_phys import Simulation
from mresim_phys.cli import main
from mresim_phys.mapgen.generate import GeneratedMap, generate
from mresim_phys.mapgen.params import MapRequest
from mresim_phys.mapgen.place import places
from mresim_phys.mapgen.sets import SplitSpec, split_of

KINDS = {"building": (300, 200), "office": (360, 160), "cave": (240, 240), "rubble": (300, 220)}


def made(kind: str, seed: int = 3, **params: object) -> GeneratedMap:
    width, height = KINDS[kind]
    return generate(MapRequest(kind=kind, seed=seed, width=width, height=height, params=params))  # type: ignore[arg-type]


def check_playable(m: GeneratedMap) -> None:
    """One open space; the base and starts on places a body fits, all in one component."""
    _, count = ndimage.label(~m.occupied, structure=ndimage.generate_binary_structure(2, 1))
    assert count == 1
    room = places(m.occupied, m.request.radius)
    cells = [(int(y), int(x)) for x, y in [m.base, *m.starts]]
    assert all(room[r, c] for r, c in cells)  # free, with the body's clearance
    reach, _ = ndimage.label(room, structure=ndimage.generate_binary_structure(2, 1))
    assert len({reach[r, c] for r, c in cells}) == 1  # one component: all reachable
    gaps = [np.hypot(a[0] - b[0], a[1] - b[1]) for i, a in enumerate(cells) for b in cells[i + 1 :]]
    assert min(gaps) >= 2 * m.request.radius + 1
    assert len(m.starts) == m.request.robots


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_every_kind_is_one_space_with_free_reachable_places(kind: str) -> None:
    check_playable(made(kind))


@settings(max_examples=12, deadline=None)
@given(
    kind=st.sampled_from(sorted(KINDS)),
    seed=st.integers(0, 10**6),
    width=st.integers(120, 320),
    height=st.integers(100, 260),
)
def test_any_seed_and_size_gives_a_playable_map(
    kind: str, seed: int, width: int, height: int
) -> None:
    request = MapRequest(kind=kind, seed=seed, width=width, height=height)  # type: ignore[arg-type]
    try:
        m = generate(request)
    except ValueError as exc:  # too small for the defaults: refused, naming why
        assert "give" in str(exc)
        return
    check_playable(m)


def test_buildings_have_rooms_doors_and_loops() -> None:
    """One open space, which walls grown by 5 cells (closing every 8-cell door) cut into
    many rooms; with loops, more doors than a tree of the rooms needs."""
    tree, loops = made("building", loops=0.0), made("building", loops=1.0)
    for m in (tree, loops):
        assert ndimage.label(~m.occupied)[1] == 1
        assert ndimage.label(~ndimage.binary_dilation(m.occupied, iterations=5))[1] >= 8
    assert np.count_nonzero(~loops.occupied) > np.count_nonzero(~tree.occupied)


def test_the_same_seed_gives_the_same_bytes_in_another_process(tmp_path: Path) -> None:
    for kind in sorted(KINDS):
        w, h = KINDS[kind]
        args = [kind, "--seed", "11", "--size", f"{w}x{h}"]
        assert main(["make-map", *args, "--out", str(tmp_path / "a" / kind)]) == 0
        other = ["make-map", *args, "--out", str(tmp_path / "b" / kind)]
        code = f"from mresim_phys.cli import main; main({other!r})"
        subprocess.run([sys.executable, "-c", code], check=True, capture_output=True)
        for name in ("map.png", "map.yaml"):
            here, there = (tmp_path / side / kind / name for side in ("a", "b"))
            assert here.read_bytes() == there.read_bytes()
    assert made("cave", seed=1).sha256 != made("cave", seed=2).sha256


def test_the_written_scenario_runs_from_the_written_places(tmp_path: Path) -> None:
    assert (
        main(["make-map", "office", "--seed", "2", "--size", "360x160", "--out", str(tmp_path)])
        == 0
    )
    meta = yaml.safe_load((tmp_path / "map.yaml").read_text())
    image = cv2.imread(str(tmp_path / "map.png"), cv2.IMREAD_GRAYSCALE)
    assert image is not None and image.shape == (160, 360)
    assert meta["kind"] == "office" and meta["params"]["door"] == 8 and len(meta["starts"]) == 4
    sim = Simulation.from_yaml(tmp_path / "scenario.yaml", steps=40)
    assert sim.base.position == tuple(meta["base"])
    record = sim.run()
    assert record.explored > 0.1


@pytest.mark.parametrize(
    ("args", "named"),
    [
        (["building", "--size", "60x45"], "give a size of at least"),
        (["building", "--size", "30x300"], "width"),
        (["office", "--size", "300x200", "--set", "rooms=3"], "rooms"),
        (["building", "--size", "300x200", "--set", "door=4"], "door (4) is narrower"),
        (["building", "--size", "300x200", "--set", "room_max=20"], "room_max"),
        (["cave", "--size", "200x200", "--set", "fill=0.7", "--set", "min_open=0.9"], "min_open"),
        (["rubble", "--size", "60x60", "--robots", "250"], "robots"),
        (["building", "--size", "300"], "WxH"),
    ],
)
def test_a_bad_request_is_one_paragraph_naming_the_parameter_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str], named: str
) -> None:
    with pytest.raises(SystemExit) if named == "WxH" else nullcontext():
        code = main(["make-map", *args, "--out", str(tmp_path)])
        assert code == 2
    err = capsys.readouterr().err
    assert named in err and "Traceback" not in err
    assert not (tmp_path / "map.png").exists()


def test_the_docs_list_every_parameter_with_its_default() -> None:
    from mresim_phys.mapgen.params import KINDS

    page = (Path(__file__).resolve().parent.parent / "docs" / "procedural-maps.md").read_text()
    for kind, model in KINDS.items():
        section = page.split(f"### `{kind}`", 1)[1].split("###", 1)[0]
        for name, field in model.model_fields.items():
            assert f"| `{name}` | `{field.default}` |" in section, (kind, name)


@pytest.mark.parametrize(
    "shape", ["loop", "corridor", "corner", "room", "loop+room", "corner+room"]
)
def test_blueprints_are_playable(shape: str) -> None:
    request = MapRequest(kind="blueprint", width=240, height=160, params={"shape": shape})
    check_playable(generate(request))


def test_a_loop_blueprint_has_a_loop() -> None:
    """The rock the ring goes round touches no outer wall: a robot can go round it."""
    m = generate(MapRequest(kind="blueprint", width=240, height=160, params={"shape": "loop"}))
    rock, count = ndimage.label(m.occupied)
    outer = rock[0, 0]
    assert count == 2 and outer != 0 and (rock[80, 120] not in (0, outer))


def write_set(folder: Path, **fields: object) -> Path:
    data = {
        "name": "t",
        "instances": [
            {"kind": "building", "size": [200, 150], "seeds": 4},
            {"kind": "blueprint", "size": [200, 150], "params": {"shape": "loop"}, "seeds": [3]},
        ],
        "split": {"test": 0.4, "seed": 1},
        **fields,
    }
    path = folder / "set.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_a_set_writes_every_instance_with_a_seeded_split(tmp_path: Path) -> None:
    path = write_set(tmp_path)
    assert main(["make-set", str(path), "--out", str(tmp_path / "a")]) == 0
    assert main(["make-set", str(path), "--out", str(tmp_path / "b")]) == 0
    index = yaml.safe_load((tmp_path / "a" / "set.yaml").read_text())
    assert (tmp_path / "a" / "set.yaml").read_bytes() == (tmp_path / "b" / "set.yaml").read_bytes()
    items = index["instances"]
    assert len(items) == 5 and len({i["id"] for i in items}) == 5
    assert (index["train"], index["test"]) == (3, 2)
    for item in items:
        assert (tmp_path / "a" / item["id"] / "map.png").is_file()
        alone = MapRequest(
            kind=item["kind"], seed=item["seed"], width=200, height=150, params=item["params"]
        )
        assert generate(alone).sha256 == item["grid_sha256"]
    sides = {seed: split_of(20, SplitSpec(test=0.25, seed=seed)) for seed in range(4)}
    assert all(s.count("test") == 5 for s in sides.values())
    assert len({tuple(s) for s in sides.values()}) > 1  # the split moves with its seed
    assert split_of(2, SplitSpec(test=0.01, seed=0)).count("test") == 1  # one each side


@pytest.mark.parametrize(
    ("instances", "named"),
    [
        ([{"kind": "castle", "size": [200, 150], "seeds": 2}], "instances.0.kind"),
        ([{"kind": "building", "size": [200, 150], "seeds": 2, "params": {"rooms": 3}}], "rooms"),
        ([{"kind": "building", "size": [42, 42], "seeds": 1}], "instances[0]"),
    ],
)
def test_a_bad_set_file_is_one_paragraph_naming_the_entry_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], instances: object, named: str
) -> None:
    path = write_set(tmp_path, instances=instances)
    assert main(["make-set", str(path), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert named in err and "set.yaml" in err and "Traceback" not in err


def test_a_set_takes_map_files_with_seeded_places(tmp_path: Path) -> None:
    """Real maps (the corpus, the original's maps fetched by the user) join a set as files:
    the grid as read, the base and starts drawn from each seed, on places a body fits."""
    root = Path(__file__).resolve().parent.parent / "maps"
    data = {
        "name": "files",
        "instances": [
            {"kind": "file", "map": str(root / "office.png"), "seeds": 2},
            {"kind": "file", "map": "../maps/corpus/aws_small_house.yaml", "seeds": [0]},
        ],
        "split": {"test": 0.34, "seed": 0},
    }
    path = tmp_path / "sets" / "set.yaml"
    path.parent.mkdir()
    (tmp_path / "maps").symlink_to(root)
    path.write_text(yaml.safe_dump(data))
    assert main(["make-set", str(path), "--out", str(tmp_path / "out")]) == 0
    index = yaml.safe_load((tmp_path / "out" / "set.yaml").read_text())
    assert [i["kind"] for i in index["instances"]] == ["file"] * 3
    metas = [
        yaml.safe_load((tmp_path / "out" / i["id"] / "map.yaml").read_text())
        for i in index["instances"]
    ]
    assert metas[0]["base"] != metas[1]["base"] or metas[0]["starts"] != metas[1]["starts"]
    for item, meta in zip(index["instances"], metas, strict=True):
        image = cv2.imread(str(tmp_path / "out" / item["id"] / "map.png"), cv2.IMREAD_GRAYSCALE)
        room = places(image == 0, 2.0)
        cells = [(int(y), int(x)) for x, y in [meta["base"], *meta["starts"]]]
        assert all(room[r, c] for r, c in cells)
        reach, _ = ndimage.label(room, structure=ndimage.generate_binary_structure(2, 1))
        assert len({reach[r, c] for r, c in cells}) == 1


def test_a_file_instance_without_its_map_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = write_set(tmp_path, instances=[{"kind": "file", "seeds": 1}])
    assert main(["make-set", str(path), "--out", str(tmp_path / "o")]) == 2
    assert "map: FILE" in capsys.readouterr().err
