"""Ground classes and what each robot can cross (``ground/``): the class grid from an image
and regions, each robot's own passable set and speed, motion that never enters ground a
robot cannot cross, the explorable area without ground no robot crosses, bad input, and a
run that replays as live."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pytest
import yaml
from test_dynamic_render import assert_replay_equals_live

from mresim_phys import Simulation
from mresim_phys.cli import main
from mresim_phys.ground.feature import GROUND
from mresim_phys.ground.grid import Access, ground_of
from mresim_phys.ground.spec import GroundSpec
from mresim_phys.knowledge.known_area import grow_known
from mresim_phys.strategies import Decision
from mresim_phys.strategies.base import PlanContext
from mresim_phys.types import FREE, OCCUPIED

SCENARIOS = Path(__file__).resolve().parent.parent / "scenarios"
MIXED = SCENARIOS / "33_rubble_mixed_team.yaml"


def classes_visited(seed: int, steps: int | None = None) -> dict[str, set[str]]:
    """Run scenario 33 with ``seed``: the classes each robot's centre stood on."""
    sim = Simulation.from_yaml(MIXED, seed=seed, **({"steps": steps} if steps else {}))
    ground = sim.setup.ground
    assert ground is not None
    names = ("floor", *ground.names)
    seen: dict[str, set[str]] = {r.name: set() for r in sim.robots}
    for _ in sim.iterate():
        for robot in sim.robots:
            seen[robot.name].add(names[ground.class_at(robot.position)])
    return seen


def test_the_grid_takes_the_legend_colours_then_the_regions(tmp_path: Path) -> None:
    image = np.full((40, 60, 3), 255, np.uint8)  # BGR on disk
    image[5:15, 5:25] = (60, 110, 150)  # rubble, RGB (150, 110, 60)
    image[20:30, 30:50] = (0, 0, 255)  # red, not in the legend: floor
    cv2.imwrite(str(tmp_path / "g.png"), image)
    spec = GroundSpec(
        classes={"rubble": 0.5, "stairs": 0.0},
        image=tmp_path / "g.png",
        legend={"rubble": (150, 110, 60)},
        regions=[{"ground": "stairs", "box": [10, 10, 20, 12]}],  # type: ignore[list-item]
    )
    ground = ground_of(spec, (40, 60))
    assert ground is not None and ground.names == ("rubble", "stairs")
    assert (ground.grid[5:10, 5:25] == 1).all() and (ground.grid[20:30, 30:50] == 0).all()
    assert (ground.grid[10:12, 10:20] == 2).all()  # the region wins over the image
    assert (ground.grid[12:15, 10:20] == 1).all()


def test_a_robots_access_takes_its_crosses_over_the_defaults() -> None:
    spec = GroundSpec(classes={"rubble": 0.0, "water": 0.0}, regions=[
        {"ground": "rubble", "box": [0, 0, 10, 10]}, {"ground": "water", "box": [10, 0, 20, 10]},
    ])  # type: ignore[list-item]  # fmt: skip
    ground = ground_of(spec, (10, 30))
    assert ground is not None
    wheels, tracks = Access.of(ground, None), Access.of(ground, {"rubble": 0.25})
    assert wheels.barred[:, :20].all() and not wheels.barred[:, 20:].any()
    assert wheels.slowness is None
    assert tracks.barred[:, 10:20].all() and not tracks.barred[:, :10].any()
    assert tracks.slowness is not None and np.allclose(tracks.slowness[:, :10], 4.0)
    assert tracks.factor_at(ground.grid, (5.5, 5.5)) == 0.25


def test_planning_leaves_out_the_ground_a_robot_cannot_cross() -> None:
    sim = Simulation.from_yaml(MIXED, steps=5)
    sim.run()
    wheels, drone = sim.robot("W1"), sim.robot("Q")
    rows, cols = sim.world.occupied.shape
    for robot in (wheels, drone):
        robot.belief[:] = FREE  # as if it knew the whole site
        robot.belief[sim.world.occupied] = OCCUPIED
        grow_known(robot.features, (0, rows, 0, cols))  # a write outside the phases
    stairs = sim.setup.ground.grid == 2  # type: ignore[union-attr]
    assert not (PlanContext(sim.view_of(wheels)).passable & stairs).any()
    assert (PlanContext(sim.view_of(drone)).passable & stairs).any()
    path = PlanContext(sim.view_of(wheels)).plan_to(290, 420)  # north of the stairs
    assert (
        len(path)
        and not stairs[np.floor(path[:, 1]).astype(int), np.floor(path[:, 0]).astype(int)].any()
    )


def test_a_move_into_ground_it_cannot_cross_is_refused_and_marks_no_wall() -> None:
    sim = Simulation.from_yaml(MIXED, steps=30)
    wheels = sim.robot("W1")
    wheels.position = (400.0, 332.0)  # just south of the stairs (y 300..330)
    sim.world.place_robots([r.position for r in sim.robots])
    go = Decision(path=np.array([[400.0, 310.0]]), goal=(400.0, 310.0))
    sim.step({"W1": go})
    assert wheels.status == "error" and len(wheels.path) == 0
    assert wheels.position[1] >= 330.0  # it never entered the stairs
    ghost = (wheels.belief == OCCUPIED) & ~sim.world.occupied
    assert not ghost[322:336, 392:408].any()  # no wall marked where it stopped


def test_a_robot_moves_at_its_own_factor_of_the_ground_it_stands_on() -> None:
    sim = Simulation.from_yaml(MIXED, steps=30)
    tracked = sim.robot("T")
    tracked.position = (150.0, 60.0)  # in the rubble band
    sim.world.place_robots([r.position for r in sim.robots])
    go = Decision(path=np.array([[150.0, 40.0]]), goal=(150.0, 40.0))
    before = tracked.distance
    sim.step({"T": go})
    assert tracked.distance - before == pytest.approx(4 * 0.4)


@pytest.mark.parametrize("seeds", [range(3)])
def test_wheels_never_enter_the_ground_they_cannot_cross(seeds: range) -> None:
    for seed in seeds:
        seen = classes_visited(seed, steps=150)
        assert seen["W1"] | seen["W2"] == {"floor"}, seed
        assert seen["T"] <= {"floor", "rubble", "stairs"}, seed


@pytest.mark.slow
def test_in_20_seeds_wheels_never_enter_stairs_while_the_drone_does() -> None:
    drone_on_stairs = 0
    for seed in range(20):
        seen = classes_visited(seed)
        assert "stairs" not in seen["W1"] | seen["W2"], seed
        assert seen["W1"] | seen["W2"] == {"floor"}, seed
        drone_on_stairs += "stairs" in seen["Q"]
    assert drone_on_stairs >= 3


def test_ground_no_robot_crosses_is_not_explorable(scenario_file: Callable[..., Path]) -> None:
    """Water nobody crosses in the door between the rooms map's two rooms: the explorable
    area drops what only a robot standing beyond it could see, so 'explored' can still
    reach 1; a team with a robot that crosses it keeps the whole area."""
    water = {"classes": {"water": 0.0}, "regions": [{"ground": "water", "box": [36, 22, 46, 40]}]}
    with_water = Simulation.from_yaml(scenario_file(ground=water))
    plain = Simulation.from_yaml(scenario_file())
    assert with_water.coverage.total < plain.coverage.total
    crossing = Simulation.from_yaml(scenario_file(ground=water, team={
        "speed": 2, "radius": 1.0, "sensor": {"range": 30}, "comm_range": 20,
        "crosses": {"water": 1.0}}))  # fmt: skip
    assert crossing.coverage.total == plain.coverage.total


def test_same_seed_same_bytes_with_and_without_threads(tmp_path: Path) -> None:
    outs = []
    for threads in ("1", "2"):
        out = tmp_path / f"run{threads}"
        args = ["run", str(MIXED), "--out", str(out), "--quiet", "--no-plots", "--steps", "60"]
        assert main([*args, "--threads", threads]) == 0
        logged = (out / "log" / "steps.jsonl").read_bytes()
        outs.append(((out / "metrics.csv").read_bytes(), logged))
    assert outs[0] == outs[1]


def test_the_mixed_team_replays_as_live(tmp_path: Path) -> None:
    data = yaml.safe_load(MIXED.read_text())
    data["steps"] = 40
    data["map"]["image"] = str((MIXED.parent / data["map"]["image"]).resolve())
    short = tmp_path / "mixed.yaml"
    short.write_text(yaml.safe_dump(data, sort_keys=False))
    assert_replay_equals_live(short, tmp_path / "run", (5, 20, 40))


def test_frames_shade_the_ground_classes(tmp_path: Path) -> None:
    out = tmp_path / "run"
    args = ["run", str(MIXED), "--out", str(out), "--quiet", "--no-plots", "--steps", "3"]
    assert main([*args, "--snapshot", "3", "--layers", "all"]) == 0
    shaded = cv2.imread(str(out / "step-00003.png"))
    assert (
        main([*args, "--snapshot", "3", "--layers", "all,-ground", "--out", str(tmp_path / "b")])
        == 0
    )
    plain = cv2.imread(str(tmp_path / "b" / "step-00003.png"))
    assert shaded is not None and plain is not None and shaded.shape == plain.shape
    assert np.abs(shaded.astype(int) - plain.astype(int)).sum() > 0


@pytest.mark.parametrize(
    ("changes", "field"),
    [
        ({"team": {"crosses": {"lava": 0.5}}}, "'lava'"),
        ({"team": {"crosses": {"rubble": 1.5}}}, "crosses"),
        (
            {
                "ground": {
                    "classes": {"rubble": 0},
                    "regions": [{"ground": "mud", "box": [0, 0, 5, 5]}],
                }
            },
            "mud",
        ),
        ({"ground": {"classes": {"rubble": 0}, "image": "g.png"}}, "legend"),
        (
            {
                "ground": {
                    "classes": {"Rubble": 0},
                    "regions": [{"ground": "Rubble", "box": [0, 0, 5, 5]}],
                }
            },
            "ground.classes",
        ),
        (
            {
                "ground": {
                    "classes": {"rubble": 0},
                    "image": "small.png",
                    "legend": {"rubble": [1, 2, 3]},
                }
            },
            "ground.image",
        ),
    ],
)
def test_bad_ground_input_is_one_paragraph_naming_the_field_and_exit_2(
    scenario_file: Callable[..., Path], capsys: pytest.CaptureFixture[str], changes: Any, field: str
) -> None:
    team = {"speed": 2, "radius": 1.0, "sensor": {"range": 30}, "comm_range": 20}
    ground = {"classes": {"rubble": 0.0}, "regions": [{"ground": "rubble", "box": [0, 0, 5, 5]}]}
    changes = {"ground": ground, **changes}
    changes["team"] = {**team, **changes.get("team", {})}
    path = scenario_file(**changes)
    cv2.imwrite(str(path.parent / "small.png"), np.zeros((10, 10, 3), np.uint8))
    assert main(["run", str(path), "--out", str(path.parent / "o"), "--quiet", "--no-plots"]) == 2
    err = capsys.readouterr().err
    assert field in err and "Traceback" not in err and "scenario.yaml" in err


def test_crosses_without_a_ground_block_is_an_error(
    scenario_file: Callable[..., Path], capsys: pytest.CaptureFixture[str]
) -> None:
    team = {"speed": 2, "radius": 1.0, "sensor": {"range": 30}, "crosses": {"rubble": 0.5}}
    assert main(["validate", str(scenario_file(team=team))]) == 2
    assert "no 'ground:' block" in capsys.readouterr().err


def test_the_feature_records_each_robots_factors() -> None:
    sim = Simulation.from_yaml(MIXED, steps=2)
    record = sim.run()
    factors = {r.name: GROUND.of(r) for r in record.robots}
    assert factors["W1"] is not None and factors["W1"].factors == (1.0, 0.0, 0.0, 0.0)
    assert factors["T"] is not None and factors["T"].factors == (1.0, 0.4, 0.25, 0.0)
    assert factors["Q"] is not None and factors["Q"].factors == (1.0, 1.0, 1.0, 1.0)
