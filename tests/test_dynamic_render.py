"""A changing world on screen: moving obstacles, doors and debris in frames, logs and replays.

One small scenario built here (an 80x60 map of two rooms and a doorway): a 4x4 cart goes
back and forth on waypoints, the doorway's door closes at step 10 and opens at step 30, a
10x10 box of rubble falls at step 20 and part of the middle wall gives way at step 25.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pytest
import yaml
from conftest import csv_row
from test_runlog import assert_same_snapshot, kept

from mresim_phys.cli import main
from mresim_phys.output.logformat import VERSION
from mresim_phys.output.runlog import RunLog, RunLogWriter, recompute_metrics
from mresim_phys.render import DEFAULT_STYLE, Renderer, frame_scale, parse_layers
from mresim_phys.render.draw import world_legend
from mresim_phys.sim import Simulation
from mresim_phys.snapshot import Snapshot

ROOT = Path(__file__).resolve().parent.parent
STEPS, SCALE = 60, 8  # the 80x60 map is drawn at 8 pixels a cell (640x480)
MAP_ONLY = "walls,unexplored,team_known,known_at_base,obstacles,doors,debris"
LEAF = (slice(25, 37), slice(40, 42))  # the door's cells off the walls (the doorway)
RUBBLE = (slice(40, 50), slice(60, 70))  # collapse at step 20
GAVE_WAY = (slice(5, 10), slice(40, 42))  # the middle wall opens here at step 25
STYLE = DEFAULT_STYLE


def two_rooms() -> np.ndarray:
    """60x80: outer walls, a middle wall at columns 40-41 with a doorway at rows 25-36."""
    occ = np.zeros((60, 80), dtype=bool)
    occ[:2, :] = occ[-2:, :] = True
    occ[:, :2] = occ[:, -2:] = True
    occ[:, 40:42] = True
    occ[LEAF] = False
    return occ


def dynamic_scenario(folder: Path, **changes: Any) -> Path:
    """Write the map and the scenario into ``folder`` (keyword arguments replace or add
    top-level keys); the scenario's path."""
    cv2.imwrite(str(folder / "rooms.png"), np.where(two_rooms(), 0, 255).astype(np.uint8))
    cart = {"waypoints": [[25, 8], [25, 52]], "speed": 1, "mode": "back_and_forth"}
    data = {
        "name": "dynamic",
        "seed": 5,
        "steps": STEPS,
        "stop": {"all_done": False},  # every step is run: the events come at steps 10-30
        "map": {"image": "rooms.png", "resolution": 0.1},
        "base_station": {"position": [8, 30], "comm_range": 30},
        "team": {"speed": 2, "radius": 1.0, "sensor": {"range": 30}, "comm_range": 30},
        "robots": [
            {"name": "A", "start": [8, 20], "heading_deg": 0},
            {"name": "B", "start": [8, 40], "heading_deg": 0},
        ],
        "obstacles": [{"name": "cart", "shape": {"box": [4, 4]}, "motion": cart}],
        "doors": [{"name": "gate", "between": [[41, 24], [41, 38]], "thickness": 2}],
        "events": [
            {"step": 10, "close": "gate"},
            {"step": 30, "open": "gate"},
            {"step": 20, "collapse": {"box": [60, 40, 70, 50]}},
            {"step": 25, "collapse": {"box": [40, 5, 42, 10]}, "becomes": "free"},
        ],
    }
    path = folder / "dynamic.yaml"
    path.write_text(yaml.safe_dump(data | changes, sort_keys=False))
    return path


def live_run(path: Path, layers: str) -> tuple[list[Snapshot], list[np.ndarray]]:
    """Every step's snapshot (copied) and frame, rendered as the run goes."""
    sim = Simulation.from_yaml(path)
    renderer = Renderer(sim.world.shape, parse_layers(layers), frame_scale(sim.world.shape, 1))
    snaps, frames = [kept(sim.snapshot())], [renderer.render(sim.snapshot())]
    for _ in range(STEPS):
        sim.step()
        snap = sim.snapshot()
        world = {m.name: (m.row, m.col) for m in sim.world.movables.values()}
        shown = {m.name: m.at for m in snap.movables if m.on}
        assert shown == world, snap.step  # the snapshot's movables are the world's
        snaps.append(kept(snap))
        frames.append(renderer.render(snap))
    return snaps, frames


@pytest.fixture(scope="module")
def scenario(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return dynamic_scenario(tmp_path_factory.mktemp("dynamic"))


@pytest.fixture(scope="module")
def map_frames(scenario: Path) -> tuple[list[Snapshot], list[np.ndarray]]:
    return live_run(scenario, MAP_ONLY)


def cell_colours(frame: np.ndarray) -> np.ndarray:
    """(60, 80, 3) colour at the centre pixel of every cell."""
    return frame[SCALE // 2 :: SCALE, SCALE // 2 :: SCALE][:60, :80]


def is_colour(cells: np.ndarray, colour: tuple[int, int, int]) -> np.ndarray:
    return np.all(cells == np.array(colour, dtype=np.uint8), axis=-1)


def test_the_scenario_does_what_the_tests_expect(map_frames: tuple[list[Snapshot], list]) -> None:
    snaps, _ = map_frames
    door = {s.step: m.on for s in snaps for m in s.movables if m.kind == "door"}
    assert not door[9] and door[10] and door[29] and not door[30]
    assert snaps[19].rubble is None and snaps[20].rubble is not None
    assert snaps[20].rubble[RUBBLE].all() and snaps[20].rubble.sum() == 100
    assert snaps[25].gave_way is not None and snaps[25].gave_way[GAVE_WAY].all()
    places = {m.at for s in snaps for m in s.movables if m.kind == "obstacle"}
    assert len(places) > 20  # the cart moved


def test_the_cart_is_drawn_where_it_is_at_every_step(
    map_frames: tuple[list[Snapshot], list[np.ndarray]],
) -> None:
    for snap, frame in zip(*map_frames, strict=True):
        (cart,) = [m for m in snap.movables if m.kind == "obstacle"]
        want = np.zeros((60, 80), dtype=bool)
        if cart.on:
            want[cart.at[0] : cart.at[0] + 4, cart.at[1] : cart.at[1] + 4] = cart.cells
        drawn = is_colour(cell_colours(frame), STYLE.obstacle)
        assert np.array_equal(drawn, want), snap.step
        assert cart.on or snap.step == 0  # on the map from step 0


def test_a_closed_door_is_door_coloured_and_an_open_one_a_dashed_line(
    map_frames: tuple[list[Snapshot], list[np.ndarray]],
) -> None:
    _, frames = map_frames
    for step in (5, 9, 30, 45):  # open: the doorway is not wall nor door; dashes on its line
        cells = cell_colours(frames[step])[LEAF]
        assert not is_colour(cells, STYLE.door).any(), step
        assert not is_colour(cells, STYLE.wall).any(), step
        column = frames[step][25 * SCALE : 37 * SCALE, 41 * SCALE]  # the door's line, x = 41
        dashes = is_colour(column, STYLE.door)
        assert 0.2 < dashes.mean() < 0.8, step  # drawn and gaps
    for step in (10, 20, 29):  # closed: every doorway cell is door-coloured, its jambs walls
        cells = cell_colours(frames[step])
        assert is_colour(cells[LEAF], STYLE.door).all(), step
        assert is_colour(cells[22:25, 40:42], STYLE.wall).all(), step
        assert is_colour(cells[37:40, 40:42], STYLE.wall).all(), step


def test_rubble_is_drawn_as_it_falls_and_gone_walls_are_not_walls(
    map_frames: tuple[list[Snapshot], list[np.ndarray]],
) -> None:
    _, frames = map_frames
    before, after = cell_colours(frames[19]), cell_colours(frames[20])
    assert not is_colour(before[RUBBLE], STYLE.rubble).any()
    assert is_colour(after[RUBBLE], STYLE.rubble).all()
    assert is_colour(after, STYLE.rubble).sum() == 100  # nothing else
    assert is_colour(cell_colours(frames[24])[GAVE_WAY], STYLE.wall).all()
    opened = cell_colours(frames[25])
    assert not is_colour(opened[GAVE_WAY], STYLE.wall).any()
    assert is_colour(opened[12:20, 40:42], STYLE.wall).all()  # the rest of the wall stays
    assert is_colour(cell_colours(frames[STEPS])[RUBBLE], STYLE.rubble).all()


def test_the_world_layers_can_be_turned_off(scenario: Path) -> None:
    """Without them, obstacles, closed doors and rubble are walls like any other."""
    snaps, frames = live_run(scenario, "walls,unexplored,team_known,known_at_base")
    cells = cell_colours(frames[20])
    (cart,) = [m for m in snaps[20].movables if m.kind == "obstacle"]
    r, c = cart.at
    assert is_colour(cells[r : r + 4, c : c + 4], STYLE.wall).all()
    assert is_colour(cells[LEAF], STYLE.wall).all()
    assert is_colour(cells[RUBBLE], STYLE.wall).all()
    assert not is_colour(frames[35], STYLE.door).any()  # no dashed line either
    assert not is_colour(frames[35], STYLE.obstacle).any()


def test_the_legend_names_the_world_layers_only_when_there_is_something(
    map_frames: tuple[list[Snapshot], list[np.ndarray]],
) -> None:
    snaps, _ = map_frames
    every = parse_layers("all").global_layers
    assert world_legend(snaps[19], every) == ("obstacle", "door")
    assert world_legend(snaps[20], every) == ("obstacle", "door", "rubble")
    assert world_legend(snaps[20], every - {"doors"}) == ("obstacle", "rubble")
    assert "obstacles" in parse_layers("default").global_layers  # on by default
    assert {"obstacles", "doors", "debris"}.isdisjoint(
        parse_layers("-obstacles,-doors,-debris").global_layers
    )


def test_replayed_snapshots_and_frames_equal_the_live_ones(scenario: Path, tmp_path: Path) -> None:
    snaps, frames = live_run(scenario, "all")
    sim = Simulation.from_yaml(scenario)
    rows = [csv_row(sim.record)]
    with RunLogWriter(tmp_path / "log", sim.snapshot(), name="dynamic", seed=5) as writer:
        for _ in range(STEPS):
            rows.append(csv_row(sim.step()))
            writer.write(sim.snapshot())
    log = RunLog.open(tmp_path / "log")
    renderer = Renderer(log.truth.shape, parse_layers("all"), frame_scale(log.truth.shape, 1))
    replayed = log.snapshots()
    for got, want, frame in zip(replayed, snaps, frames, strict=True):
        assert_same_snapshot(got, want)
        assert np.array_equal(renderer.render(got), frame), want.step
    assert [csv_row(record) for record in recompute_metrics(log)] == rows


def test_the_log_stores_footprints_once_and_moves_only_when_they_change(
    scenario: Path, tmp_path: Path
) -> None:
    assert main(["run", str(scenario), "--out", str(tmp_path), "--quiet", "--no-plots"]) == 0
    meta = json.loads((tmp_path / "log" / "meta.json").read_text())
    assert meta["version"] == VERSION
    assert [(m["name"], m["kind"], m["shape"]) for m in meta["movables"]] == [
        ("cart", "obstacle", [4, 4]),
        ("gate", "door", [16, 2]),
    ]
    lines = (tmp_path / "log" / "steps.jsonl").read_text().splitlines()
    moved = {json.loads(line)["step"]: json.loads(line).get("moved") for line in lines}
    door_moves = [step for step, m in moved.items() if m and any(i == 1 for i, *_ in m)]
    assert door_moves == [0, 10, 30]  # listed at the start, then when it closed and opened
    assert all(len(m) <= 2 for m in moved.values() if m)


def test_cli_replay_frames_and_metrics_equal_the_live_run(scenario: Path, tmp_path: Path) -> None:
    assert_replay_equals_live(scenario, tmp_path / "run", (5, 10, 20, 25, 30, 44, 60))


def test_replayed_regions_pass_through_obstacles_radio_passes_through(tmp_path: Path) -> None:
    """Path-loss region polygons replay as live around an obstacle with
    ``blocks_radio: false`` (radio passes it, the truth holds it), with random debris."""
    walk = {"random_walk": [60, 20], "speed": 1.5}
    rover = {"name": "rover", "shape": {"circle": 1.5}, "motion": walk, "blocks_radio": False}
    path = dynamic_scenario(
        tmp_path,
        communication={"model": "path_loss"},
        obstacles=[rover],
        random_debris={"rate": 0.3, "size": [2, 4]},
    )
    assert_replay_equals_live(path, tmp_path / "run", (10, 20, 33, 38))


def assert_replay_equals_live(scenario: Path, out: Path, steps: tuple[int, ...]) -> None:
    """Run, replay with --metrics: the same metrics and PNG frames at ``steps``."""
    flags = ["--snapshot", ",".join(map(str, steps)), "--layers", "all"]
    assert main(["run", str(scenario), "--out", str(out), "--quiet", "--no-plots", *flags]) == 0
    assert main(["replay", str(out), *flags, "--metrics"]) == 0
    assert (out / "metrics-replayed.csv").read_bytes() == (out / "metrics.csv").read_bytes()
    for step in steps:
        live = cv2.imread(str(out / f"step-{step:05d}.png"))
        replayed = cv2.imread(str(out / f"replay-step-{step:05d}.png"))
        assert live is not None and np.array_equal(live, replayed), step


def test_version_2_logs_replay_without_movables(scenario: Path, tmp_path: Path) -> None:
    """A log as version 2 wrote it (no movables, rubble or gave-way) still replays."""
    assert main(["run", str(scenario), "--out", str(tmp_path), "--quiet", "--no-plots"]) == 0
    log_dir = tmp_path / "log"
    meta = json.loads((log_dir / "meta.json").read_text())
    del meta["movables"]
    (log_dir / "meta.json").write_text(json.dumps(meta | {"version": 2}))
    lines = [json.loads(line) for line in (log_dir / "steps.jsonl").read_text().splitlines()]
    for line in lines:
        line.pop("moved", None)
    (log_dir / "steps.jsonl").write_text("".join(json.dumps(line) + "\n" for line in lines))
    for path in log_dir.glob("deltas-*.npz"):
        with np.load(path) as data:
            kept_arrays = {k: data[k] for k in data.files if not k.startswith(("rubble", "gave"))}
        np.savez_compressed(path, **kept_arrays)
    snaps = list(RunLog.open(log_dir).snapshots())
    assert len(snaps) == STEPS + 1
    assert all(s.movables == () and s.rubble is None and s.gave_way is None for s in snaps)


@pytest.mark.parametrize(
    ("name", "steps", "layers", "scale"),
    [("01_quickstart", 40, "all", None), ("02_office_frontier", 25, "default", 0.5)],
)
def test_static_frames_are_unchanged(
    name: str, steps: int, layers: str, scale: float | None
) -> None:
    """Frames of shipped static scenarios do not change with the world layers: they equal
    the same frame drawn without them, and the reference frames in tests/data (first
    written by the code of commit 1cc4d1a, before the world layers existed; re-rendered when
    the frontier rule changed the runs themselves, when the legend gained the done,
    idle and stuck glyphs and labels that would overlap were placed apart, and when rays
    grazing a wall corner stopped marking the free cell beyond it as wall; when maps
    of known resolution gained a scale bar; and when frontiers were weighed by the
    seen-but-unvisited region they border, which moved the runs; when the legend gained
    the fruitless glyph; when candidate_power 2 became the default, which moved the
    runs; and when the `all` layers gained `ghost_walls`, walls a map holds where the
    truth is free)."""
    sim = Simulation.from_yaml(ROOT / "scenarios" / f"{name}.yaml", steps=steps)
    for _ in range(steps):
        sim.step()
    shape = sim.world.shape
    renderer = Renderer(shape, parse_layers(layers), scale or frame_scale(shape, 1))
    frame = renderer.render(sim.snapshot())
    reference = cv2.imread(str(ROOT / "tests" / "data" / f"{name}-step{steps}-{layers}.png"))
    assert np.array_equal(frame, reference)
    plain = parse_layers(f"{layers},-obstacles,-doors,-debris,-terrain")
    without = Renderer(shape, plain, scale or frame_scale(shape, 1)).render(sim.snapshot())
    assert np.array_equal(frame, without)
