"""``role_based`` with ``rendezvous: multi_point``: explorer and relay meet at two points the
comm estimate links through a wall, the relay's nearest the base's range; backup meetings;
the potential, agreed and through-wall points reach the video layers and the run log."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mresim_phys.cli import main
from mresim_phys.errors import ScenarioError
from mresim_phys.knowledge.teammates import PAYLOAD
from mresim_phys.output.runlog import RunLog
from mresim_phys.planning.grid import bbox
from mresim_phys.sim import Simulation
from mresim_phys.strategies.meetings import Rendezvous
from mresim_phys.strategies.rendezvous import linked, relay_point
from mresim_phys.types import FREE, OCCUPIED

MakeScenario = Callable[..., Path]
MULTI = {"name": "role_based", "params": {"rendezvous": "multi_point"}}


def u_corridor() -> np.ndarray:
    """Two west-east corridors joined at their east end, a 2-cell wall between them."""
    belief = np.full((60, 80), OCCUPIED, dtype=np.uint8)
    belief[20:30, 4:76] = FREE  # upper corridor
    belief[32:42, 4:76] = FREE  # lower corridor (the base's)
    belief[20:42, 66:76] = FREE  # the join at the east end
    return belief


def test_the_relays_point_is_across_the_wall_nearest_the_bases_range() -> None:
    belief = u_corridor()
    passable = belief == FREE
    explorer, base = (45.5, 21.5), (5.5, 40.5)
    choice = relay_point(belief, passable, bbox(passable), explorer, base, reach=24.0)
    assert choice.relay[1] > 32  # in the base's corridor, not a walk round the join away
    assert 27 < choice.relay[0] < explorer[0]  # as near the base's range as the link allows
    here, there = np.array([explorer]), np.array([choice.relay])
    assert linked(belief, here[0], there, 24.0)[0]  # the estimate links the two points
    assert len(choice.through_walls) and (choice.through_walls[:, 1] > 32).all()
    assert len(choice.candidates) >= 10  # about one per DENSITY passable cells, 16 at least drawn


def test_no_link_through_a_thick_wall() -> None:
    belief = u_corridor()
    belief[30:32, :] = OCCUPIED
    belief[28:34, 4:60] = OCCUPIED  # the wall is now 6 cells thick but still one wall
    belief[10:50, 30:34] = OCCUPIED  # and a second wall across both corridors
    far = np.array([[50.5, 37.5]])
    assert not linked(belief, np.array([10.5, 25.5]), far, 30.0)[0]  # two walls: out of reach


def pair(scenario_file: MakeScenario, **changes: Any) -> Path:
    data: dict[str, Any] = {
        "steps": 500,
        "stop": {"known_at_base": 0.95},
        "base_station": {"position": [6, 30], "comm_range": 6},
        "team": {"speed": 2, "radius": 1.0, "sensor": {"range": 15}, "comm_range": 6,
                 "strategy": MULTI},
        "robots": [
            {"name": "R", "start": [10, 30], "role": "relay", "parent": "base"},
            {"name": "E", "start": [12, 34], "parent": "R"},
        ],
        "communication": {"model": "path_loss"},
    }  # fmt: skip
    return scenario_file(**(data | changes))


def test_a_multi_point_pair_agrees_two_points_and_a_backup(scenario_file: MakeScenario) -> None:
    sim = Simulation.from_yaml(pair(scenario_file))
    agreements, relay_states = [], set()
    while not sim.finished():
        sim.step()
        payload = PAYLOAD.state_of(sim.robot("E").features)
        if isinstance(payload, Rendezvous) and payload.backup is not None:
            agreements.append(payload)
        relay_states.add(sim.robot("R").strategy.state)  # type: ignore[attr-defined]
    assert agreements and {"carry", "wait"} <= relay_states
    assert all(a.backup is not None and a.backup.step > a.step for a in agreements)
    assert sim.record.known_at_base >= 0.95  # the goal within the cap


def test_a_relay_whose_explorer_fails_tries_the_backup_then_explores(
    scenario_file: MakeScenario,
) -> None:
    sim = Simulation.from_yaml(pair(scenario_file, events=[{"step": 40, "fail": "E"}]))
    states = []
    while not sim.finished():
        sim.step()
        relay = sim.robot("R").strategy
        meeting = relay.meeting  # type: ignore[attr-defined]
        states.append((sim.t, relay.state, meeting))  # type: ignore[attr-defined]
    backups = [t for t, _, m in states if m is not None and m.backup is None and t > 40]
    explored = [t for t, s, _ in states if s == "explore" and t > 40]
    assert backups and explored and explored[-1] > backups[0]  # backup, then on its own
    assert sim.t < 500  # it did not wait forever: the goal was reached


def test_the_rendezvous_layers_are_logged_and_replayed(
    scenario_file: MakeScenario, tmp_path: Path
) -> None:
    path = pair(scenario_file, steps=80)
    out = tmp_path / "run"
    assert main(["run", str(path), "--out", str(out), "--quiet", "--no-plots"]) == 0
    snaps = list(RunLog.open(out / "log").snapshots())
    explorer = [s.robots[1] for s in snaps]
    assert any(r.rv_candidates is not None and len(r.rv_candidates) for r in explorer)
    assert any(r.rendezvous is not None and len(r.rendezvous) == 3 for r in explorer)
    assert any(r.rv_through_walls is not None for r in explorer)


def test_multi_point_without_relays_is_an_error(scenario_file: MakeScenario) -> None:
    loners = [{"name": "A", "start": [10, 30]}, {"name": "B", "start": [12, 34]}]
    with pytest.raises(ScenarioError, match="A, B use the strategy role_based"):
        Simulation.from_yaml(pair(scenario_file, robots=loners))
