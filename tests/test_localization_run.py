"""Robots that do not know exactly where they are, in a run (issue 31): drift, mapping at
the believed pose, corrections, logs and bad input."""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from conftest import QUICKSTART

from mresim_phys import Simulation
from mresim_phys.cli import main
from mresim_phys.errors import ScenarioError
from mresim_phys.knowledge.mapping import integrate_scan
from mresim_phys.knowledge.scanfold import fold_placed, scan_into_map
from mresim_phys.localization.corrections import landmark_fixes
from mresim_phys.localization.estimate import PoseEstimate
from mresim_phys.localization.feature import LOCALIZATION, Localization, localize
from mresim_phys.localization.perceive import as_believed
from mresim_phys.localization.scan_match import LiveField, likelihood_field
from mresim_phys.localization.spec import LocalizationSpec
from mresim_phys.output.localization import consistency
from mresim_phys.scenario.load import load_scenario
from mresim_phys.sweeps.tables import flatten_summary
from mresim_phys.types import FREE, OCCUPIED, UNKNOWN
from mresim_phys.world.sensing import scan
from mresim_phys.world.space import World

ScenarioFile = Callable[..., Path]
DRIFT = {"odometry": {"alpha": [0.001, 0.00001, 0.001, 0.00001]}}


def core(sim: Simulation, steps: int) -> list[tuple[Any, ...]]:
    """Each step's explored and known-at-base figures and every robot's true pose."""
    rows = []
    for record in sim.iterate():
        poses = tuple((r.position, r.heading) for r in sim.robots)
        rows.append((record.explored, record.known_at_base, poses))
        if record.step >= steps:
            break
    return rows


def errors(sim: Simulation) -> list[float]:
    """Each robot's position error now."""
    states = [LOCALIZATION.state_of(r.features) for r in sim.robots]
    return [s.error()[0] for s in states if s is not None]


def test_zero_alphas_are_the_noise_free_run_step_for_step() -> None:
    exact = core(Simulation.from_yaml(QUICKSTART), 60)
    zero = {"team.localization": {"odometry": {"alpha": [0, 0, 0, 0]}}}
    assert core(Simulation.from_yaml(QUICKSTART, **zero), 60) == exact


def test_drift_moves_the_body_off_the_believed_pose_and_the_map_with_it() -> None:
    """With drift the true and believed poses part; each robot's map is drawn where it
    believes it was, so it holds walls where the truth has none (ghost walls)."""
    sim = Simulation.from_yaml(QUICKSTART, **{"team.localization": DRIFT})
    core(sim, 80)
    assert min(errors(sim)) > 0.5
    truth = sim.world.occupied
    ghosts = [int(np.count_nonzero((r.belief == OCCUPIED) & ~truth)) for r in sim.robots]
    exact = Simulation.from_yaml(QUICKSTART)
    core(exact, 80)
    sharp = [int(np.count_nonzero((r.belief == OCCUPIED) & ~truth)) for r in exact.robots]
    assert min(ghosts) > 3 * max(max(sharp), 10), (ghosts, sharp)


def test_a_scan_folds_at_the_believed_pose_in_one_call_as_on_the_slow_path() -> None:
    """The one-call fold placed at a believed pose gives the very map the cast, the scan
    turned and moved (``as_believed``) and the separate fold give."""
    sim = Simulation.from_yaml(QUICKSTART, **{"team.localization": DRIFT})
    robot = sim.robots[0]
    loc = LOCALIZATION.state_of(robot.features)
    assert loc is not None
    x, y = robot.position
    loc.estimate = PoseEstimate((x + 2.3, y - 1.7, robot.heading + 0.2), loc.estimate.cov)
    laser, rays = robot.laser, sim.senses.filter_of(robot)
    one = np.zeros_like(robot.belief), np.zeros_like(robot.safe)
    scan_into_map(sim.world, robot.position, robot.heading, laser, rays, *one, loc.believed)
    slow = np.zeros_like(robot.belief), np.zeros_like(robot.safe)
    cast = scan(sim.world, robot.position, robot.heading, laser, rays)
    integrate_scan(*slow, as_believed(cast, loc), laser.safe_fraction)
    assert np.array_equal(one[0], slow[0]) and np.array_equal(one[1], slow[1])
    placed = np.zeros_like(robot.belief), np.zeros_like(robot.safe)
    fold_placed(cast, robot.heading, laser, *placed, loc.believed)  # after a scan match
    assert np.array_equal(one[0], placed[0]) and np.array_equal(one[1], placed[1])
    moved = np.zeros_like(robot.belief), np.zeros_like(robot.safe)
    integrate_scan(*moved, cast, laser.safe_fraction)
    assert not np.array_equal(one[0], moved[0])  # the placement moved the walls


def drive(loc: Localization, legs: list[tuple[float, float]]) -> None:
    """Drive ``loc`` along ``legs`` (believed-frame points), as ``motion.py`` does."""
    for end in legs:
        leg = loc.leg(end)
        loc.arrive(*leg, loc.drive(*leg))


def test_the_drift_of_many_runs_spreads_as_the_filter_predicts() -> None:
    """400 robots drive the same 12 legs from the same start, each with its own stream:
    their true end positions spread round the believed one with the covariance the
    estimate predicts (within 20 %), and every believed pose is the same."""
    spec = LocalizationSpec.model_validate({"odometry": {"alpha": [0.0005, 0.00005, 0.01, 0.0005]}})
    legs = [(10.0 + 3 * i, 20.0 + (i % 3) * 2.0) for i in range(12)]
    ends, believed, predicted = [], set(), None
    for k in range(400):
        streams = (
            np.random.default_rng(k),
            np.random.default_rng(10_000 + k),
            np.random.default_rng(0),
        )
        loc = localize(spec, (8.0, 20.0, 0.0), streams, (200.0, 200.0))
        drive(loc, legs)
        ends.append(loc.true[:2])
        believed.add(loc.believed)
        predicted = loc.estimate.cov[:2, :2]
    assert len(believed) == 1 and predicted is not None
    mean = np.array(next(iter(believed))[:2])
    spread = np.cov((np.array(ends) - mean).T)
    assert np.allclose(spread, predicted, rtol=0.2, atol=0.02 * predicted.max())


def test_a_base_fix_pulls_the_error_down_to_the_measurement_noise() -> None:
    """Robots whose belief is 30 cells off with a wide covariance, one base fix each
    (sigma 0.5): the error left has the fix's spread (RMS sigma * sqrt 2, within 15 %)."""
    spec = LocalizationSpec.model_validate(
        {"odometry": {"alpha": [0.01, 0, 0.01, 0]}, "corrections": [{"kind": "base", "within": 50}]}
    )
    world = World(np.zeros((100, 100), dtype=bool), [1.0])
    left = []
    for k in range(600):
        loc = localize(spec, (50.0, 50.0, 0.0), (np.random.default_rng(k),) * 3, (100.0, 100.0))
        loc.estimate = PoseEstimate((80.0, 50.0, 0.0), np.diag([900.0, 900.0, 0.01]))
        landmark_fixes(loc, (45.0, 50.0), world, world.query_filter(None, False))
        left.append(loc.error()[0])
        assert loc.corrected == {"base": 1}
    rms = math.sqrt(float(np.mean(np.square(left))))
    assert rms == pytest.approx(0.5 * math.sqrt(2), rel=0.15)


def test_a_beacon_fixes_only_in_line_of_sight_and_range() -> None:
    occupied = np.zeros((60, 60), dtype=bool)
    occupied[:, 30] = True  # a wall between the robot and the second beacon
    world = World(occupied, [1.0])
    spec = LocalizationSpec.model_validate(
        {"corrections": [{"kind": "beacons", "positions": [[20, 10], [45, 20], [20, 55]],
                          "range": 30, "sigma": 0.5}]}
    )  # fmt: skip
    loc = localize(spec, (20.0, 20.0, 0.0), (np.random.default_rng(1),) * 3, (60.0, 60.0))
    loc.estimate = PoseEstimate((25.0, 20.0, 0.0), np.diag([100.0, 100.0, 0.01]))
    landmark_fixes(loc, (0.5, 0.5), world, world.query_filter(None, False))
    assert loc.corrected == {"beacon": 1}  # the first: the second is walled off, the third far
    assert loc.error()[0] < 2.0


def test_a_teammate_on_a_link_corrects_a_lost_robot(scenario_file: ScenarioFile) -> None:
    """Two robots linked all run long: B drifts and sees A (who knows its pose) on the
    link; with the teammate correction its error stays a fraction of the one without."""
    drift = {"odometry": {"alpha": [0.004, 0.0001, 0.004, 0.0001]}}
    fix = {**drift, "corrections": [{"kind": "teammate"}]}
    runs = {}
    for name, block in (("alone", drift), ("teammate", fix)):
        robots = [
            {"name": "A", "start": [8, 20], "heading_deg": 0},
            {"name": "B", "start": [8, 40], "heading_deg": 0, "localization": block},
        ]
        sim = Simulation(load_scenario(scenario_file(robots=robots, steps=60)))
        core(sim, 60)
        state = LOCALIZATION.state_of(sim.robots[1].features)
        assert state is not None
        runs[name] = (state.error()[0], dict(state.corrected))
    assert runs["teammate"][1].get("teammate", 0) > 20
    assert runs["teammate"][0] < 0.5 * runs["alone"][0], runs


def test_scan_matching_holds_the_drift_down() -> None:
    matching = {**DRIFT, "corrections": [{"kind": "scan_matching"}]}
    alone = Simulation.from_yaml(QUICKSTART, **{"team.localization": DRIFT})
    core(alone, 100)
    matched = Simulation.from_yaml(QUICKSTART, **{"team.localization": matching})
    core(matched, 100)
    assert max(errors(matched)) < 0.5 * min(errors(alone)), (errors(matched), errors(alone))


def test_the_live_field_is_the_likelihood_field_over_its_box() -> None:
    """A map edited at random, the field refreshed over a box after each edit: inside
    the box it equals the field computed from scratch."""
    rng = np.random.default_rng(3)
    belief = np.full((70, 90), UNKNOWN, dtype=np.uint8)
    live = LiveField(belief.shape, 1.3)
    for _ in range(25):
        r, c = rng.integers(0, 70), rng.integers(0, 90)
        belief[max(r - 3, 0) : r + 3, max(c - 3, 0) : c + 3] = rng.choice([FREE, OCCUPIED])
        box = (int(rng.integers(0, 30)), int(rng.integers(40, 70)), int(rng.integers(0, 40)),
               int(rng.integers(50, 90)))  # fmt: skip
        field = live.refresh(belief, box)
        want = likelihood_field(belief, 1.3)
        assert np.allclose(field[box[0] : box[1], box[2] : box[3]],
                           want[box[0] : box[1], box[2] : box[3]])  # fmt: skip


def test_same_seed_same_bytes_on_one_thread_or_two(tmp_path: Path) -> None:
    block = {**DRIFT, "corrections": [{"kind": "teammate"}, {"kind": "scan_matching"}]}
    data = yaml.safe_load(QUICKSTART.read_text())
    data["map"]["image"] = str((QUICKSTART.parent / data["map"]["image"]).resolve())
    data["team"]["localization"], data["steps"] = block, 40
    outputs = []
    for threads in (1, 2):
        path, out = tmp_path / f"t{threads}.yaml", tmp_path / f"t{threads}"
        path.write_text(yaml.safe_dump({**data, "simulation": {"threads": threads}}))
        assert main(["run", str(path), "--out", str(out), "--quiet", "--no-plots"]) == 0
        summary = json.loads((out / "summary.json").read_text())
        for key in ("wall_time_s", "steps_per_second"):
            summary.pop(key)
        outputs.append(((out / "metrics.csv").read_bytes(), summary))
    assert outputs[0] == outputs[1]
    header = outputs[0][0].splitlines()[0].decode()
    assert "pose_error_A" in header and "pose_error_max" in header
    assert set(outputs[0][1]["localization"]["robots"]) == {"A", "B"}


@pytest.mark.parametrize(
    ("block", "field"),
    [
        ({"odometry": {"alpha": [-0.1, 0, 0, 0]}}, "localization.odometry.alpha"),
        ({"odometry": {"alpha": [float("nan"), 0, 0, 0]}}, "localization.odometry.alpha"),
        ({"corrections": [{"kind": "base", "sigma": float("inf")}]}, "corrections[0].base.sigma"),
        ({"corrections": [{"kind": "teammate", "sigma_range": -1}]}, "sigma_range"),
        ({"corrections": [{"kind": "gps"}]}, "localization.corrections[0]"),
        ({"corrections": [{"kind": "beacons", "positions": [[41, 10]]}]}, "positions[0]"),
        ({"corrections": [{"kind": "beacons", "positions": [[500, 30]]}]}, "positions[0]"),
    ],
)
def test_bad_localization_input_is_one_paragraph_naming_the_field(
    scenario_file: ScenarioFile,
    capsys: pytest.CaptureFixture[str],
    block: dict[str, Any],
    field: str,
) -> None:
    path = scenario_file(team={"speed": 2, "radius": 1.0, "localization": block})
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err
    assert str(path) in err and field in err, err
    assert "Traceback" not in err
    with pytest.raises(ScenarioError):
        Simulation(load_scenario(path))


def test_a_robot_s_block_merges_into_the_team_s(scenario_file: ScenarioFile) -> None:
    team = {"speed": 2, "radius": 1.0, "localization": {**DRIFT, "corrections": [{"kind": "base"}]}}
    robots = [
        {"name": "A", "start": [8, 20]},
        {"name": "B", "start": [8, 40], "localization": {"corrections": []}},
    ]
    scenario = load_scenario(scenario_file(team=team, robots=robots))
    a, b = (r.localization for r in scenario.robots)
    assert a is not None and b is not None
    assert a.odometry == b.odometry and len(a.corrections) == 1 and b.corrections == []


def test_units_in_metres_scale_the_alphas_and_the_corrections(scenario_file: ScenarioFile) -> None:
    """At 0.1 m a cell: a2 (rad^2 per m^2) becomes a2 / 100 per cell^2, a4 (m^2 per
    rad^2) 100 * a4, a base fix within 2 m within 20 cells with sigma 5 cells."""
    block = {"odometry": {"alpha": [0.1, 1.0, 0.1, 0.01]},
             "corrections": [{"kind": "base", "within": 2.0, "sigma": 0.5}]}  # fmt: skip
    path = scenario_file(
        units="m", base_station={"position": [0.85, 3.05], "comm_range": 2.0},
        team={"speed": 0.2, "radius": 0.1, "localization": block}, dt=1.0,
        robots=[{"name": "A", "start": [0.85, 4.05]}],
    )  # fmt: skip
    spec = load_scenario(path).robots[0].localization
    assert spec is not None
    assert spec.odometry.alpha == pytest.approx((0.1, 0.01, 0.1, 1.0))
    fix = spec.corrections[0]
    assert fix.kind == "base" and (fix.within, fix.sigma) == pytest.approx((20.0, 5.0))


def test_a_turn_in_place_turns_both_poses() -> None:
    spec = LocalizationSpec.model_validate({"odometry": {"alpha": [0.0, 0.0, 0.0, 0.0]}})
    loc = localize(spec, (5.0, 5.0, 0.0), (np.random.default_rng(0),) * 3, (20.0, 20.0))
    assert loc.turn(1.0) == 1.0 and loc.believed == (5.0, 5.0, 1.0) == loc.true
    noisy = localize(
        LocalizationSpec.model_validate({"odometry": {"alpha": [0.05, 0, 0, 0]}}),
        (5.0, 5.0, 0.0), (np.random.default_rng(0),) * 3, (20.0, 20.0),
    )  # fmt: skip
    true = noisy.turn(1.0)
    assert noisy.believed[2] == 1.0 and true != 1.0 and noisy.estimate.cov[2, 2] > 0


def ghost_walls(sim: Simulation) -> dict[str, int]:
    """Per robot: cells its map holds as walls that are free in truth."""
    truth = sim.world.occupied
    return {r.name: int(np.count_nonzero((r.belief == OCCUPIED) & ~truth)) for r in sim.robots}


def test_a_frozen_localisation_smears_its_map_while_its_teammate_s_stays_sharp(
    scenario_file: ScenarioFile,
) -> None:
    """A's localisation freezes at step 5 (no ``localization:`` block: the fault gives it
    one without drift); it drives and maps from a belief that stands still. B, untouched,
    keeps a sharp map; A's error grows with the distance it drives."""
    event = {"step": 5, "fail": "A", "part": "localization", "mode": "frozen"}
    quiet = {"speed": 2, "radius": 1.0, "sensor": {"range": 30}, "comm_range": 0}
    base = {"position": [8, 30], "comm_range": 0}  # no link: B never merges A's map
    path = scenario_file(events=[event], team=quiet, base_station=base, steps=60)
    sim = Simulation(load_scenario(path))
    core(sim, 5)
    held = LOCALIZATION.state_of(sim.robot("A").features)
    assert held is not None
    where = held.believed
    core(sim, 55)
    a = LOCALIZATION.state_of(sim.robot("A").features)
    assert a is not None and LOCALIZATION.key not in sim.robot("B").features
    assert "localization" in sim.robot("A").broken
    assert a.believed == where and a.error()[0] > 3
    ghosts = ghost_walls(sim)
    assert ghosts["A"] >= 20 and ghosts["B"] <= 2, ghosts


def test_a_jump_throws_the_belief_off_by_its_distance_at_once() -> None:
    events = [{"step": 4, "fail": "B", "part": "localization", "mode": "jump", "distance": 7.5}]
    sim = Simulation.from_yaml(QUICKSTART, events=events)
    lines = []
    for record in sim.iterate():
        lines += sim.events_now
        if record.step == 4:
            break
    b = LOCALIZATION.state_of(sim.robot("B").features)
    assert b is not None and b.error()[0] == pytest.approx(7.5)
    assert b.estimate.cov[0, 0] == 0.0  # it does not know
    assert "jump B localization 7.5 cells" in lines
    assert not sim.robot("B").broken


def test_random_localisation_jumps_come_from_the_seed(scenario_file: ScenarioFile) -> None:
    law = {"probability": 0.1, "part": "localization", "mode": "jump", "distance": 3}
    runs = []
    for _ in range(2):
        sim = Simulation(load_scenario(scenario_file(faults={"random": [law]}, steps=40)))
        lines = []
        for _record in sim.iterate():
            lines += sim.events_now
        runs.append((lines, errors(sim)))
    assert runs[0] == runs[1]
    assert sum("jump" in line for line in runs[0][0]) >= 3


@pytest.mark.parametrize(
    ("event", "words"),
    [
        ({"part": "localization"}, "needs a mode"),
        ({"part": "localization", "mode": "jump"}, "needs a distance"),
        ({"part": "localization", "mode": "jump", "distance": 3, "until": 9}, "no 'until'"),
        ({"part": "drive", "mode": "frozen"}, "go with part 'localization'"),
        ({"part": "localization", "mode": "spin"}, "events[0]"),
    ],
)
def test_bad_localisation_faults_are_one_paragraph(
    scenario_file: ScenarioFile,
    capsys: pytest.CaptureFixture[str],
    event: dict[str, Any],
    words: str,
) -> None:
    path = scenario_file(events=[{"step": 3, "fail": "A", **event}])
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err
    assert str(path) in err and "events[0]" in err and words in err, err
    assert "Traceback" not in err


SCENARIOS = QUICKSTART.parent
BY_STRATEGY = {
    "frontier": "01_quickstart.yaml",
    "random_walk": "06_small_rooms_random_walk.yaml",
    "hungarian": "19_office_hungarian.yaml",
    "min_pos": "20_office_min_pos.yaml",
    "utility_return": "21_rooms_utility_return.yaml",
    "leader_follower": "22_rooms_leader_follower.yaml",
    "role_based": "23_rooms_role_based.yaml",
    "role_switch": "25_library_role_switch.yaml",
    "sector_rendezvous": "26_rubble_sector_rendezvous.yaml",
}


@pytest.mark.parametrize("strategy", sorted(BY_STRATEGY))
def test_every_built_in_strategy_explores_under_drift_from_its_beliefs(strategy: str) -> None:
    """Each built-in strategy's shipped scenario, every robot drifting with scan matching
    and teammate fixes, 40 steps: it runs, its robots move and explore, and what each
    strategy was shown is the believed pose (a view's position is never the true one
    once they part)."""
    block = {**DRIFT, "corrections": [{"kind": "scan_matching"}, {"kind": "teammate"}]}
    sim = Simulation.from_yaml(SCENARIOS / BY_STRATEGY[strategy], **{"team.localization": block})
    record = sim.record
    for record in sim.iterate():
        if record.step >= 40:
            break
    assert record.distance > 0 and record.explored > 0.02
    parted = [r for r in sim.robots if r.alive and errors_of(r) > 0.05]
    assert parted, "no robot drifted"
    for robot in parted:
        view = sim.view_of(robot)
        assert view.position == robot.believed_position != robot.position


def errors_of(robot: Any) -> float:
    """A robot's position error."""
    state = LOCALIZATION.state_of(robot.features)
    return 0.0 if state is None else state.error()[0]


def test_map_consistency_counts_ghost_openings_and_ghost_walls() -> None:
    truth = np.zeros((6, 8), dtype=bool)
    truth[:, 4] = True  # a wall down the middle
    reachable = ~truth
    reachable[:, 5:] = False  # only the left side is reachable
    belief = np.full(truth.shape, UNKNOWN, dtype=np.uint8)
    belief[0, 4] = belief[1, 4] = FREE  # two ghost openings in the wall
    belief[2, 1] = OCCUPIED  # a ghost wall where the robots can go
    belief[3, 6] = OCCUPIED  # a wall believed where it is free but out of reach: not counted
    belief[4, 4] = OCCUPIED  # a true wall
    got = consistency(belief, truth, reachable)
    area = int(reachable.sum())
    assert got == {"false_free": 2 / area, "false_occupied": 1 / area}


def test_a_sweep_table_has_the_localisation_figures() -> None:
    robot = {"false_free": 0.1, "false_occupied": 0.3}
    block = {
        "robots": {"A": robot, "B": {"false_free": 0.3, "false_occupied": 0.1}},
        "team": {"final_mean_error": 2.0, "max_error": 9.0, "mean_error": 1.5},
        "base": {"false_free": 0.05, "false_occupied": 0.2},
    }
    row = flatten_summary({"steps": 10, "localization": block})
    assert row["pose_error_max"] == 9.0 and row["base_false_occupied"] == 0.2
    assert row["robots_false_free"] == pytest.approx(0.2)
