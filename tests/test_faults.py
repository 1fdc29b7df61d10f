"""Fault models: each part does exactly and only what it says, recovery restores it, random
failures, batteries, hazard zones and the out-of-contact rule reproduce with the seed and
do not move when the strategy changes, and bad input is one clear error."""

from __future__ import annotations

import itertools
import json
import subprocess
import sys
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from conftest import write_png
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mresim_phys import Simulation
from mresim_phys.cli import main
from mresim_phys.errors import ScenarioError
from mresim_phys.faults.battery import BATTERY
from mresim_phys.faults.clocks import FailureClock, exposure_budget
from mresim_phys.faults.spec import RandomFaultSpec
from mresim_phys.scenario.load import load_scenario
from mresim_phys.types import FREE, UNKNOWN

ScenarioFile = Callable[..., Path]
QUIET = {"speed": 2, "radius": 1.0, "sensor": {"range": 30}, "comm_range": 0}
NO_BASE_RADIO = {"position": [8, 30], "comm_range": 0}
ROOT = Path(__file__).resolve().parent.parent


def run(path: Path, steps: int) -> Simulation:
    sim = Simulation.from_yaml(path)
    for _ in range(steps):
        sim.step()
    return sim


def failure_steps(sim: Simulation, steps: int) -> list[tuple[int, str]]:
    """(step, line) of every fault line logged in ``steps`` steps."""
    out = [(0, line) for line in sim.events_now]
    for _ in range(steps):
        sim.step()
        out += [(sim.t, line) for line in sim.events_now]
    return out


# -- what each part does ---------------------------------------------------------------


def test_a_radio_dead_robot_moves_and_senses_but_exchanges_nothing(
    scenario_file: ScenarioFile,
) -> None:
    sim = Simulation.from_yaml(scenario_file(events=[{"step": 0, "fail": "B", "part": "radio"}]))
    b, a = sim.robot("B"), sim.robot("A")
    start, known = b.position, np.count_nonzero(b.belief == FREE)
    for _ in range(12):
        sim.step()
        assert not sim.links[b.index].any() and not sim.links[:, b.index].any()
        assert not sim.comm.traffic.sent[b.index].any()
        assert not sim.comm.traffic.sent[:, b.index].any()
    assert b.position != start and np.count_nonzero(b.belief == FREE) > known
    assert "B" not in a.teammates and "B" not in sim.base.teammates
    assert set(b.teammates) <= {"B"}


def test_a_sensor_dead_robot_moves_and_talks_but_its_belief_does_not_grow(
    scenario_file: ScenarioFile,
) -> None:
    path = scenario_file(
        events=[{"step": 1, "fail": "A", "part": "sensor"}], team=QUIET, base_station=NO_BASE_RADIO
    )
    sim = run(path, 1)
    robot = sim.robot("A")
    belief, scans, start = robot.belief.copy(), robot.scans, robot.position
    for _ in range(10):
        sim.step()
    assert np.array_equal(robot.belief, belief) and robot.scans == scans
    assert robot.position != start and robot.speaking


def test_a_drive_dead_robot_keeps_its_distance_and_still_talks(
    scenario_file: ScenarioFile,
) -> None:
    sim = run(scenario_file(events=[{"step": 2, "fail": "B", "part": "drive"}]), 2)
    robot = sim.robot("B")
    distance, where = robot.distance, robot.position
    for _ in range(10):
        sim.step()
        assert robot.distance == distance and robot.position == where
    assert sim.links[robot.index].any() and robot.speaking and robot.can_sense


def test_degraded_speed_and_range_are_scaled_and_seen_by_the_strategy(
    scenario_file: ScenarioFile,
) -> None:
    event = {"step": 1, "fail": "B", "part": "degraded", "speed_factor": 0.5}
    event["range_factor"] = 0.25
    sim = run(scenario_file(events=[event]), 1)
    robot = sim.robot("B")
    assert robot.speed == pytest.approx(1.5) and robot.laser.range == pytest.approx(7.5)
    view = sim.view_of(robot)
    assert view.speed == pytest.approx(1.5) and view.sensor_range == pytest.approx(7.5)
    for _ in range(8):
        before = robot.distance
        sim.step()
        assert robot.distance - before <= 1.5 + 1e-9
    assert robot.broken == {"degraded"} and robot.can_move and robot.can_sense


def test_a_degraded_range_shortens_the_scans(scenario_file: ScenarioFile) -> None:
    def known_after(events: list[dict[str, Any]]) -> int:
        path = scenario_file(events=events, team=QUIET, base_station=NO_BASE_RADIO)
        return int(np.count_nonzero(Simulation.from_yaml(path).robot("A").belief == FREE))

    event = {"step": 0, "fail": "A", "part": "degraded", "range_factor": 0.2}
    assert known_after([event]) < known_after([])


@pytest.mark.parametrize("part", ["robot", "drive", "radio", "sensor"])
def test_recovery_restores_the_part(scenario_file: ScenarioFile, part: str) -> None:
    sim = run(scenario_file(events=[{"step": 2, "fail": "B", "part": part, "until": 6}]), 5)
    robot = sim.robot("B")
    assert not {"robot": robot.alive, "drive": robot.can_move}.get(part, part not in robot.broken)
    sim.step()
    assert sim.events_now[-1] == ("recover B" if part == "robot" else f"recover B {part}")
    assert robot.alive and robot.can_move and robot.can_sense and robot.speaking
    assert robot.broken == frozenset()
    distance = robot.distance
    for _ in range(6):
        sim.step()
    assert robot.distance > distance or part == "sensor"  # it moves again


def test_two_failures_of_one_part_need_two_repairs(scenario_file: ScenarioFile) -> None:
    events = [
        {"step": 2, "fail": "B", "part": "radio", "until": 4},
        {"step": 3, "fail": "B", "part": "radio", "until": 6},
    ]
    sim = run(scenario_file(events=events), 4)
    assert "radio" in sim.robot("B").broken
    run_on = [sim.step() for _ in range(2)]
    assert run_on and "radio" not in sim.robot("B").broken


# -- random failures, common random numbers ----------------------------------------------


def random_faults(**law: Any) -> dict[str, Any]:
    return {"random": [law]}


def test_random_failures_come_from_the_seed_alone(scenario_file: ScenarioFile) -> None:
    path = scenario_file(steps=120, faults=random_faults(mtbf=30, part="radio", recover_after=5))
    first = failure_steps(Simulation.from_yaml(path), 100)
    again = failure_steps(Simulation.from_yaml(path), 100)
    assert first == again and any("fail A radio" in line for _, line in first)
    other = failure_steps(Simulation.from_yaml(path, seed=4), 100)
    assert other != first


def test_the_same_seed_gives_the_same_failure_steps_in_another_process(
    scenario_file: ScenarioFile,
) -> None:
    path = scenario_file(steps=60, faults=random_faults(shape=1.5, scale=25))
    code = (
        "import json, sys\nfrom mresim_phys import Simulation\n"
        f"sim = Simulation.from_yaml({str(path)!r})\nout = []\n"
        "for _ in range(50):\n    sim.step()\n"
        "    out += [[sim.t, line] for line in sim.events_now]\nprint(json.dumps(out))\n"
    )
    env_path = {"PYTHONPATH": str(ROOT)}
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env_path
    )
    there = [tuple(pair) for pair in json.loads(result.stdout)]
    here = failure_steps(Simulation.from_yaml(path), 50)[
        len(Simulation.from_yaml(path).events_now) :
    ]
    assert there == here and there


@pytest.mark.parametrize(
    "faults",
    [
        random_faults(mtbf=20, robots=["A", "B"]),
        random_faults(probability=0.05, part="sensor"),
        {"hazards": [{"region": {"box": [0, 0, 80, 60]}, "probability": 0.08}]},
    ],
)
def test_failures_do_not_move_when_the_strategy_changes(
    scenario_file: ScenarioFile, faults: dict[str, Any]
) -> None:
    """Same exposure (a hazard zone over the whole map; clocks in steps): the same steps."""
    lines = []
    for strategy in ("frontier", "random_walk"):
        team = {"speed": 2, "radius": 1.0, "sensor": {"range": 30}, "strategy": strategy}
        path = scenario_file(steps=80, faults=faults, team=team, stop={"all_done": False})
        lines.append(failure_steps(Simulation.from_yaml(path), 70))
    assert lines[0] == lines[1] and lines[0]


def test_clocks_are_keyed_by_robot_name_not_team_order(scenario_file: ScenarioFile) -> None:
    faults = random_faults(mtbf=25)
    robots = [
        {"name": "A", "start": [8, 20], "heading_deg": 0},
        {"name": "B", "start": [8, 40], "heading_deg": 0},
    ]
    one = Simulation.from_yaml(scenario_file(faults=faults, robots=robots)).setup.faults
    two = Simulation.from_yaml(scenario_file(faults=faults, robots=robots[::-1])).setup.faults
    assert one is not None and two is not None
    assert {c.robot: c.next_fail for c in one.clocks} == {c.robot: c.next_fail for c in two.clocks}


def test_a_clock_repairs_and_stops_at_max_failures() -> None:
    law = RandomFaultSpec(mtbf=10, recover_after=3, max_failures=2, part="drive")
    clock = FailureClock("A", law, np.random.default_rng(1))
    acts = [(t, what) for t in range(1, 500) if (what := clock.due(t)) is not None]
    assert [what for _, what in acts] == ["fail", "repair", "fail", "repair"]
    assert acts[1][0] == acts[0][0] + 3 and acts[3][0] == acts[2][0] + 3


def test_a_clock_without_recovery_fails_once_and_never_after_until() -> None:
    law = RandomFaultSpec(probability=0.5, after=10, until=12)
    acts = []
    for seed in range(30):
        clock = FailureClock("A", law, np.random.default_rng(seed))
        acts.append([t for t in range(200) if clock.due(t) is not None])
    assert all(len(a) <= 1 and all(11 <= t <= 12 for t in a) for a in acts)
    assert any(acts)


def test_exposure_budget_is_geometric() -> None:
    rng = np.random.default_rng(0)
    draws = [exposure_budget(0.1, rng) for _ in range(4000)]
    assert min(draws) >= 1 and abs(np.mean(draws) - 10) < 0.6
    assert exposure_budget(0.0, rng) > 10**15


# -- hazards, batteries, contact ------------------------------------------------------------


def test_a_hazard_zone_fails_a_robot_only_inside_it(scenario_file: ScenarioFile) -> None:
    zone = {"region": {"box": [0, 0, 80, 60]}, "probability": 1.0, "robots": ["B"]}
    sim = Simulation.from_yaml(scenario_file(faults={"hazards": [zone]}))
    assert sim.events_now == ["fail B (hazard 0)"] and sim.robot("A").alive
    far = {"region": {"box": [70, 50, 80, 60]}, "probability": 1.0}
    sim = run(scenario_file(faults={"hazards": [far]}, steps=20), 10)
    assert all(r.alive for r in sim.robots)
    assert sim.hazards is not None and sim.hazards[55, 75] == 1.0 and sim.hazards[0, 0] == 0


def test_a_hazard_can_fail_one_part(scenario_file: ScenarioFile) -> None:
    zone = {"region": {"circle": [8, 40, 5]}, "probability": 1.0, "part": "radio"}
    sim = Simulation.from_yaml(scenario_file(faults={"hazards": [zone]}))
    assert sim.events_now == ["fail B radio (hazard 0)"] and not sim.robot("B").speaking


def test_a_battery_drains_with_motion_scans_and_messages_then_the_robot_fails(
    scenario_file: ScenarioFile,
) -> None:
    battery = {"capacity": 30, "per_cell": 1.0, "per_scan": 0.1, "per_message": 0.5}
    sim = Simulation.from_yaml(scenario_file(faults={"battery": battery}, steps=60))
    a = sim.robot("A")
    levels = [BATTERY.value_in(a.features)]
    while a.alive and sim.t < 40:
        sim.step()
        levels.append(BATTERY.value_in(a.features))
    assert levels[0] is not None and levels[0] < 1.0  # step 0: a scan and messages
    assert all(x is not None and y is not None and y <= x for x, y in itertools.pairwise(levels))
    assert not a.alive and BATTERY.value_in(a.features) == 0.0
    assert f"fail {a.name} (battery empty)" in sim.events_now
    assert a.distance <= 30 and BATTERY.of(sim.view_of(sim.robot("B"))) is not None


def test_battery_is_none_without_one_and_only_for_the_listed_robots(
    scenario_file: ScenarioFile,
) -> None:
    sim = Simulation.from_yaml(scenario_file())
    assert BATTERY.of(sim.view_of(sim.robot("A"))) is None
    faults = {"battery": {"capacity": 100, "robots": ["B"]}}
    sim = Simulation.from_yaml(scenario_file(faults=faults))
    assert "battery" not in sim.robot("A").features and "battery" in sim.robot("B").features


def test_a_robot_out_of_contact_too_long_fails(scenario_file: ScenarioFile) -> None:
    faults = {"fail_if_out_of_contact_for": 5}
    sim = Simulation.from_yaml(scenario_file(faults=faults, team=QUIET, base_station=NO_BASE_RADIO))
    lines = failure_steps(sim, 8)
    assert lines == [
        (6, "fail A (out of contact for 5 steps)"),
        (6, "fail B (out of contact for 5 steps)"),
    ]
    linked = Simulation.from_yaml(scenario_file(faults=faults))
    assert failure_steps(linked, 10) == []  # A and B stay in range of each other


# -- nobody is told ----------------------------------------------------------------------------


def test_teammates_are_not_told_only_silence_then_presumed_lost(
    scenario_file: ScenarioFile,
) -> None:
    path = scenario_file(
        events=[{"step": 3, "fail": "B"}], simulation={"presume_lost_after": 5}, steps=40
    )
    sim = run(path, 3)
    heard = sim.robot("A").teammates["B"]
    assert heard.state != "failed"
    for _ in range(4):
        sim.step()
    assert sim.robot("A").teammates["B"] == heard
    assert "B" not in sim.view_of(sim.robot("A")).lost
    for _ in range(4):
        sim.step()
    assert "B" in sim.view_of(sim.robot("A")).lost


# -- bad input ------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("changes", "field"),
    [
        ({"events": [{"step": 3, "fail": "Z"}]}, "events[0].fail"),
        ({"events": [{"step": 3, "fail": "A", "part": "wheel"}]}, "events[0].part"),
        ({"events": [{"step": 5, "fail": "A", "until": 5}]}, "events[0]"),
        ({"events": [{"step": 5, "fail": "A", "part": "degraded"}]}, "events[0]"),
        ({"events": [{"step": 5, "fail": "A", "speed_factor": 0.5}]}, "events[0]"),
        ({"faults": random_faults(mtbf=0)}, "faults.random[0].mtbf"),
        ({"faults": random_faults(shape=0, scale=10)}, "faults.random[0].shape"),
        ({"faults": random_faults(shape=2)}, "faults.random[0]"),
        ({"faults": random_faults(mtbf=5, probability=0.1)}, "faults.random[0]"),
        ({"faults": random_faults(probability=1.5)}, "faults.random[0].probability"),
        ({"faults": random_faults(mtbf=9, robots=["Z"])}, "faults.random[0].robots"),
        ({"faults": random_faults(mtbf=9, part="wheel")}, "faults.random[0].part"),
        ({"faults": {"battery": {"capacity": 0}}}, "faults.battery.capacity"),
        ({"faults": {"battery": {"capacity": 9, "robots": ["Q"]}}}, "faults.battery.robots"),
        (
            {"faults": {"hazards": [{"region": {"box": [0, 0, 9, 9]}, "probability": -0.1}]}},
            "faults.hazards[0].probability",
        ),
        (
            {"faults": {"hazards": [{"region": {"box": [90, 70, 99, 80]}, "probability": 0.1}]}},
            "faults.hazards[0].region",
        ),
        (
            {"events": [{"step": 4, "fail": "A", "part": "radio"}] * 2},
            "events[0] and events[1]",
        ),
        ({"faults": {"fail_if_out_of_contact_for": 0}}, "faults.fail_if_out_of_contact_for"),
    ],
)
def test_bad_fault_input_is_one_paragraph_naming_the_file_and_field(
    scenario_file: ScenarioFile,
    capsys: pytest.CaptureFixture[str],
    changes: dict[str, Any],
    field: str,
) -> None:
    path = scenario_file(**changes)
    built = ["--explorable"] if field.endswith(".region") else []  # a zone is checked on the world
    assert main(["validate", *built, str(path)]) == 2
    err = capsys.readouterr().err
    assert str(path) in err and field in err, err
    assert "Traceback" not in err
    with pytest.raises(ScenarioError):
        Simulation(load_scenario(path))


def test_the_fault_keys_round_trip(scenario_file: ScenarioFile) -> None:
    faults = {
        "random": [{"mtbf": 40, "part": "degraded", "speed_factor": 0.5, "recover_after": 9}],
        "battery": {"capacity": 100, "per_scan": 0.1},
        "hazards": [{"region": {"circle": [30, 30, 5]}, "probability": 0.2, "part": "sensor"}],
        "fail_if_out_of_contact_for": 50,
    }
    scenario = load_scenario(scenario_file(faults=faults))
    dumped = scenario.model_dump(mode="json")["faults"]
    assert load_scenario(scenario_file(faults=dumped)).faults == scenario.faults


def test_the_frontier_auction_reauctions_a_presumed_lost_teammates_frontier() -> None:
    """B, silent near the left frontier, wins it while heard from; presumed lost, A takes it."""
    from test_strategies import corridor_view

    from mresim_phys.knowledge.teammates import TeammateInfo
    from mresim_phys.strategies.frontier import FrontierExploration
    from mresim_phys.strategies.params import FrontierParams

    silent = TeammateInfo("B", (30.5, 10.5), (21.5, 10.5), "active", "explorer", step=9)
    view = corridor_view({"B": silent}, (45.5, 10.5))
    counted = FrontierExploration(FrontierParams()).decide(view)
    presumed = replace(view, features={"lost": frozenset({"B"})})
    lost = FrontierExploration(FrontierParams()).decide(presumed)
    assert counted.goal is not None and counted.goal[0] > 50
    assert lost.goal is not None and lost.goal[0] < 50


def test_the_frontier_auction_leaves_out_a_teammate_whose_drive_or_sensor_failed() -> None:
    from test_strategies import corridor_view

    from mresim_phys.knowledge.teammates import TeammateInfo
    from mresim_phys.strategies.frontier import FrontierExploration
    from mresim_phys.strategies.params import FrontierParams

    goals = {}
    for broken in ((), ("drive",), ("sensor",), ("radio",)):
        mate = TeammateInfo("B", (30.5, 10.5), None, "active", "explorer", step=9, broken=broken)
        decision = FrontierExploration(FrontierParams()).decide(
            corridor_view({"B": mate}, (45.5, 10.5))
        )
        assert decision.goal is not None
        goals[broken] = decision.goal[0] < 50
    assert goals == {(): False, ("drive",): True, ("sensor",): True, ("radio",): False}


def test_a_robot_with_a_failed_part_says_so_in_its_record(scenario_file: ScenarioFile) -> None:
    sim = run(scenario_file(events=[{"step": 2, "fail": "B", "part": "sensor"}]), 4)
    heard = sim.robot("A").teammates["B"]
    assert heard.broken == ("sensor",) and heard.state == "active" and heard.step == 4
    assert sim.robot("B").teammates["A"].broken == ()


def corridor_scenario(tmp_path: Path, lost_after: int) -> Path:
    """A 236-cell corridor; A starts heading left, B right, both in range of everyone."""
    occ = np.zeros((16, 240), dtype=bool)
    occ[:2] = occ[-2:] = True
    occ[:, :2] = occ[:, -2:] = True
    write_png(tmp_path / "corridor.png", occ)
    data = {
        "name": "corridor",
        "seed": 1,
        "steps": 400,
        "map": {"image": "corridor.png"},
        "base_station": {"position": [120, 8], "comm_range": 300},
        "team": {"speed": 2, "radius": 1.0, "sensor": {"range": 15}, "comm_range": 300},
        "robots": [
            {"name": "A", "start": [116, 8], "heading_deg": 180},
            {"name": "B", "start": [124, 8]},
        ],
        "simulation": {"presume_lost_after": lost_after},
        "stop": {"explored": 0.99},
        "events": [{"step": 12, "fail": "B"}],
    }
    path = tmp_path / "corridor.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_another_robot_explores_the_frontier_a_failed_robot_was_heading_for(
    tmp_path: Path,
) -> None:
    sim = Simulation.from_yaml(corridor_scenario(tmp_path, 20))
    for _ in range(12):
        sim.step()
    b, a = sim.robot("B"), sim.robot("A")
    assert not b.alive and b.goal is not None and b.goal[0] > 140  # mid-way to the right end
    assert a.position[0] < 100 and np.any(a.belief[8, 200:236] == UNKNOWN)
    sim.run()
    assert sim.stop_reason() == "explored" and a.position[0] > 200
    assert not np.any(a.belief[8, 200:236] == UNKNOWN)


# -- any failures leave a sound run ---------------------------------------------------------

PARTS = st.sampled_from(["robot", "drive", "sensor", "radio", "degraded"])
FAILURE = st.tuples(st.sampled_from(["A", "B", "C"]), st.integers(0, 25), PARTS, st.booleans())


def fail_event(robot: str, step: int, part: str, recovers: bool) -> dict[str, Any]:
    event: dict[str, Any] = {"step": step, "fail": robot, "part": part}
    if part == "degraded":
        event["speed_factor"] = event["range_factor"] = 0.5
    if recovers:
        event["until"] = step + 7
    return event


@settings(
    max_examples=20, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(failures=st.lists(FAILURE, max_size=6, unique_by=lambda f: (f[0], f[1], f[2])))
def test_any_failures_leave_the_run_complete_and_sound(
    scenario_file: ScenarioFile, failures: list[tuple[str, int, str, bool]]
) -> None:
    robots = [
        {"name": "A", "start": [8, 20], "heading_deg": 0},
        {"name": "B", "start": [8, 40], "heading_deg": 0},
        {"name": "C", "start": [30, 30], "heading_deg": 180},
    ]
    events = [fail_event(*f) for f in failures]
    path = scenario_file(events=events, robots=robots, steps=35, stop={"all_done": False})
    sim = Simulation.from_yaml(path)
    explored = sim.record.explored
    while not sim.finished():
        before = {r.name: (r.position, r.distance) for r in sim.robots}
        record = sim.step()
        assert record.explored >= explored - 1e-12
        assert 0 <= record.known_at_base <= record.explored + 1e-12 <= 1 + 1e-12
        explored = record.explored
        for robot in sim.robots:
            assert not sim.world.overlaps_wall(robot.position, robot.radius * 0.999)
            position, distance = before[robot.name]
            if not robot.can_move:  # failed, or its drive is (this step or before)
                assert robot.position == position and robot.distance == distance
    assert sim.t == 35


# -- shown to the eye, and replayed -------------------------------------------------------------


def test_batteries_hazards_and_partial_failures_replay_as_live(
    scenario_file: ScenarioFile, tmp_path: Path
) -> None:
    from test_dynamic_render import assert_replay_equals_live

    faults = {
        "battery": {"capacity": 60, "per_scan": 0.05, "per_message": 0.2},
        "hazards": [{"region": {"box": [50, 10, 78, 40]}, "probability": 0.2}],
    }
    events = [
        {"step": 3, "fail": "A", "part": "radio", "until": 12},
        {"step": 5, "fail": "B", "part": "degraded", "speed_factor": 0.5},
    ]
    path = scenario_file(faults=faults, events=events, steps=40, stop={"all_done": False})
    assert_replay_equals_live(path, tmp_path / "run", (4, 8, 20, 40))
    lines = (tmp_path / "run" / "log" / "steps.jsonl").read_text().splitlines()
    agents = json.loads(lines[8])["agents"]
    assert "battery" not in agents[0] and 0 < agents[1]["battery"] < 1
    assert agents[1]["parts"] == ["radio"] and agents[2]["parts"] == ["degraded"]


def test_frames_show_hazard_zones_battery_levels_and_a_ring_for_partial_failures(
    scenario_file: ScenarioFile,
) -> None:
    from mresim_phys.render import Renderer, frame_scale, parse_layers
    from mresim_phys.render.draw import robot_label, world_legend

    zone = {"region": {"box": [60, 40, 78, 58]}, "probability": 0.1}
    faults = {"battery": {"capacity": 100}, "hazards": [zone]}
    events = [{"step": 0, "fail": "B", "part": "sensor"}]
    sim = Simulation.from_yaml(scenario_file(faults=faults, events=events))
    snap = sim.snapshot()
    assert snap.hazards is not None and robot_label(snap.robots[1]).startswith("B [sensor] ")
    assert robot_label(snap.robots[0]).endswith("%")
    assert world_legend(snap, frozenset({"hazards"})) == ("hazard",)
    shape = snap.truth.shape
    frames = {}
    for layers in ("all,-legend", "all,-legend,-hazards"):
        renderer = Renderer(shape, parse_layers(layers), frame_scale(shape, 1))
        frames[layers] = renderer.render(snap)
    differ = np.any(frames["all,-legend"] != frames["all,-legend,-hazards"], axis=2)
    per_cell = renderer.map_size[0] / shape[1]  # pixels per cell
    rows, cols = np.nonzero(differ)
    assert len(rows) and rows.min() >= 40 * per_cell - 1 and cols.min() >= 60 * per_cell - 1


def test_a_drive_dead_robot_scans_where_it_stands_each_step(scenario_file: ScenarioFile) -> None:
    sim = run(scenario_file(events=[{"step": 2, "fail": "B", "part": "drive"}]), 2)
    robot = sim.robot("B")
    scans = robot.scans
    for _ in range(5):
        sim.step()
    assert robot.scans == scans + 5
