"""``sector_rendezvous``: the open space split into wedges around the base, each robot
exploring its own, ring neighbours meeting on their shared boundary; a failed robot's
wedge is shared out and nobody waits for it forever."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image

from mresim_phys.knowledge.teammates import PAYLOAD
from mresim_phys.sim import Simulation
from mresim_phys.strategies.sector import SectorPayload, SectorRendezvous, in_wedge, wedge

MakeScenario = Callable[..., Path]
BASE = (6.0, 94.0)


def test_wedges_share_the_span_without_overlap() -> None:
    order = ["A", "B", "C"]
    spans = [wedge(order, name, 270.0, 90.0) for name in order]
    bearings = np.radians(np.arange(270.5, 360.0, 1.0))
    owners = np.array([in_wedge(bearings, span) for span in spans])
    assert (owners.sum(axis=0) == 1).all()  # every bearing of the span in exactly one wedge
    assert math.isclose(spans[0][0], math.radians(270)) and math.isclose(spans[-1][1], 2 * math.pi)


def open_field(tmp_path: Path, scenario_file: MakeScenario, **changes: Any) -> Path:
    """An open 150x100 yard with a few blocks, the base in its south-west corner."""
    occupied = np.zeros((100, 150), dtype=bool)
    occupied[:1, :] = occupied[-1:, :] = occupied[:, :1] = occupied[:, -1:] = True
    for r, c in ((15, 30), (30, 60), (40, 20), (10, 70), (60, 100), (70, 40), (20, 120)):
        occupied[r : r + 4, c : c + 4] = True
    Image.fromarray(np.where(occupied, 0, 255).astype(np.uint8)).save(tmp_path / "yard.png")
    data: dict[str, Any] = {
        "steps": 1500,
        "stop": {"explored": 0.9},
        "map": {"image": "yard.png", "resolution": 0.1},
        "base_station": {"position": list(BASE), "comm_range": 25},
        "team": {
            "speed": 2, "radius": 1.0, "sensor": {"range": 10}, "comm_range": 25,
            "strategy": {"name": "sector_rendezvous",
                         "params": {"first_bearing_deg": 270, "span_deg": 90, "meet_interval": 60}},
        },
        "robots": [{"name": n, "start": [4 + 3 * i, 96], "heading_deg": -45}
                   for i, n in enumerate("ABC")],
        "communication": {"model": "path_loss"},
    }  # fmt: skip
    return scenario_file(**(data | changes))


def run(path: Path) -> tuple[Simulation, dict[str, list[bool]]]:
    """Run to the end; per robot, for each frontier it chose while its wedge held one,
    whether the chosen frontier's centre lay in its wedge."""
    sim = Simulation.from_yaml(path)
    own: dict[str, list[bool]] = {r.name: [] for r in sim.robots}
    seen: dict[str, object] = {}
    while not sim.finished():
        sim.step()
        for robot in sim.robots:
            strategy, decision = robot.strategy, robot.decision
            assert isinstance(strategy, SectorRendezvous)
            sent = PAYLOAD.state_of(robot.features)
            if isinstance(sent, SectorPayload):
                for meeting in sent.meetings:  # on a boundary of its wedge
                    x, y = meeting.point
                    if math.dist(meeting.point, BASE) > 15:
                        bearing = math.atan2(y - BASE[1], x - BASE[0]) % (2 * math.pi)
                        ends = [a % (2 * math.pi) for a in strategy.wedge.span]
                        gap = min(abs(math.remainder(bearing - end, 2 * math.pi)) for end in ends)
                        assert gap < math.radians(10), (robot.name, meeting)
            if decision is None or seen.get(robot.name) is decision or not robot.alive:
                continue
            seen[robot.name] = decision
            if "target_cluster" in decision.info:
                x, y = decision.info["frontiers"].centroids.T
                inside = in_wedge(np.arctan2(y - BASE[1], x - BASE[0]), strategy.wedge.span)
                if inside.any():
                    own[robot.name].append(bool(inside[decision.info["target_cluster"]]))
    return sim, own


def test_each_robot_explores_its_wedge_and_neighbours_meet(
    tmp_path: Path, scenario_file: MakeScenario
) -> None:
    sim, own = run(open_field(tmp_path, scenario_file))
    assert sim.record.explored >= 0.9  # the goal within the cap
    for name, flags in own.items():
        assert flags and sum(flags) >= 0.9 * len(flags), name  # its wedge's frontiers first
    met = {r.name: r.strategy.met for r in sim.robots}  # type: ignore[attr-defined]
    assert sum(met.values()) >= 2  # neighbours kept meetings
    payloads = [PAYLOAD.state_of(r.features) for r in sim.robots]
    assert all(isinstance(p, SectorPayload) for p in payloads)


def test_a_failed_robots_wedge_is_shared_out(tmp_path: Path, scenario_file: MakeScenario) -> None:
    """B fails at step 30 and is presumed lost 40 steps later: while A and C hear from each
    other, they share the 90 degrees, 45 each (a robot that has not heard from the other
    for 40 steps presumes it lost too and takes the whole span, so the split is checked
    while both count each other; it shows from A's next replan on)."""
    path = open_field(
        tmp_path, scenario_file, events=[{"step": 30, "fail": "B"}],
        simulation={"presume_lost_after": 40},
    )  # fmt: skip
    sim = Simulation.from_yaml(path)
    shared = []
    while not sim.finished():
        sim.step()
        a = sim.robots[0]
        heard_c = a.teammates.get("C")
        if sim.t > 75 and heard_c is not None and sim.t - heard_c.step <= 30:
            span = a.strategy.wedge.span  # type: ignore[attr-defined]
            shared.append(math.isclose(span[1] - span[0], math.radians(45)))
    # two share 90 degrees while they count each other (from the replan after contact)
    assert len(shared) >= 20 and sum(shared) >= 0.8 * len(shared)
    assert sim.record.explored >= 0.9 and sim.t < 1500  # nobody waited for B forever
