"""Bounded links (``comms/queued.py``): capacity, radio capacity, latency, priorities, and
a ledger that never counts a cell as delivered before it arrives."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mresim_phys import Simulation
from mresim_phys.agents import Agent, empty_belief
from mresim_phys.cli import main
from mresim_phys.comms.exchange import CELL_BYTES, hop_groups
from mresim_phys.comms.ledger import NEVER, Ledger
from mresim_phys.comms.queued import QueuedExchange, fitting
from mresim_phys.comms.radio import LinkLayer
from mresim_phys.comms.radio_params import RadioSpec
from mresim_phys.types import FREE, UNKNOWN

SHAPE = (20, 20)


def make_agents(n: int) -> list[Agent]:
    agents = []
    for i in range(n):
        belief, safe = empty_belief(SHAPE)
        agents.append(Agent(f"a{i}", i, (float(i), 0.0), 1.0, belief, safe, "explorer"))
    return agents


class Bounded:
    """Agents exchanged through a queued exchange, their maps edited by hand."""

    def __init__(self, agents: list[Agent], **spec: Any) -> None:
        self.agents = agents
        self.ledger = Ledger(SHAPE, len(agents))
        self.exchange = QueuedExchange(self.ledger, LinkLayer(RadioSpec(**spec), len(agents)))

    def __call__(self, links: np.ndarray, step: int, multi_hop: bool = True) -> Any:
        for agent in self.agents:
            self.ledger.note(agent.index, (0, SHAPE[0], 0, SHAPE[1]))
            self.ledger.stamp_sensed(agent.index, agent.belief, agent.safe, step)
        return self.exchange.run(self.agents, links, step, hop_groups(links, multi_hop))


def chain(n: int, cut: tuple[int, ...] = ()) -> np.ndarray:
    links = np.zeros((n, n), dtype=bool)
    for i in range(n - 1):
        if i not in cut:
            links[i, i + 1] = links[i + 1, i] = True
    return links


def known(agent: Agent) -> int:
    return int(np.count_nonzero(agent.belief != UNKNOWN))


def record_bytes(agent: Agent, step: int) -> int:
    return agent.own_record(step).nbytes()


@pytest.mark.parametrize(("cells", "room"), [(100, 100), (37, 50), (60, 300), (1, 5)])
def test_a_delta_of_s_bytes_arrives_in_ceil_s_over_c_steps_and_not_before(
    cells: int, room: int
) -> None:
    a, b = agents = make_agents(2)
    a.belief.reshape(-1)[:cells] = FREE
    capacity = room + record_bytes(a, 0)  # the sender's own record goes first every step
    run = Bounded(agents, capacity=capacity)
    steps = math.ceil(cells * CELL_BYTES / room)
    for step in range(steps):
        traffic = run(chain(2), step)
        assert traffic.sent[0, 1] <= capacity
        assert known(b) == min(cells, (step + 1) * (room // CELL_BYTES))
        assert (known(b) == cells) == (step == steps - 1)


def test_latency_d_delivers_at_t_plus_d_whether_or_not_the_link_holds() -> None:
    a, b = agents = make_agents(2)
    a.belief[3, :] = FREE
    run = Bounded(agents, latency=3)
    run(chain(2), 10)
    for step in (11, 12):
        run(chain(2, cut=(0,)), step)
        assert known(b) == 0 and "a0" not in b.teammates
    run(chain(2, cut=(0,)), 13)
    assert known(b) == 20 and b.teammates["a0"].step == 10


def test_latency_adds_up_over_hops() -> None:
    agents = make_agents(4)
    agents[3].belief[5, 5] = FREE
    run = Bounded(agents, latency=2)
    arrival = None
    for step in range(12):
        run(chain(4), step)
        if arrival is None and agents[0].belief[5, 5] == FREE:
            arrival = step
    assert arrival == 6  # three hops of two steps each


def test_a_cut_transfer_resumes_and_the_ledger_syncs_only_when_it_has_all_arrived() -> None:
    a, b = agents = make_agents(2)
    a.belief.reshape(-1)[:90] = FREE
    room = 150  # 30 cells a step
    run = Bounded(agents, capacity=room + record_bytes(a, 0))
    sent_cells = 0
    for step, linked in enumerate([True, False, False, True, True, False, True]):
        traffic = run(chain(2) if linked else chain(2, cut=(0,)), step)
        sent_cells += (int(traffic.sent[0, 1]) - (record_bytes(a, step) if linked else 0)) // 5
        if known(b) < 90:
            assert run.ledger.synced[0, 1] == NEVER
    assert known(b) == 90 and sent_cells == 90  # nothing sent twice
    assert run.ledger.synced[0, 1] >= 0


def test_no_cell_the_receiver_holds_is_sent_again() -> None:
    a, b = agents = make_agents(2)
    a.belief[:2, :] = FREE
    b.belief[0, :] = FREE  # b has half of it already
    run = Bounded(agents, capacity=10_000)
    traffic = run(chain(2), 0)
    assert traffic.sent[0, 1] == 20 * CELL_BYTES + record_bytes(a, 0)


def test_each_hop_respects_its_capacity_and_knowledge_crosses_hops_within_a_step() -> None:
    agents = make_agents(3)
    agents[2].belief[:4, :] = FREE  # 80 cells
    run = Bounded(agents, capacity=10_000)
    run(chain(3), 0)
    assert known(agents[0]) == 80  # latency 0: two hops in one step
    small = make_agents(3)
    small[2].belief[:4, :] = FREE
    run = Bounded(small, capacity=200)
    for step in range(6):
        traffic = run(chain(3), step)
        assert (traffic.sent <= 200).all()
    assert known(small[0]) == 80


def test_radio_capacity_bounds_what_an_agent_sends_over_all_its_links() -> None:
    agents = make_agents(3)
    agents[1].belief[:5, :] = FREE
    run = Bounded(agents, radio_capacity=300)
    links = chain(3)
    traffic = run(links, 0)
    assert traffic.sent[1].sum() <= 300 and traffic.sent[1].sum() > 200


def test_base_first_sends_what_the_base_lacks_before_the_rest() -> None:
    base, robot, other = agents = make_agents(3)
    run = Bounded(agents, capacity=10 * CELL_BYTES + 2 * record_bytes(robot, 0))
    robot.belief[0, :10] = FREE
    run(chain(2), 0)  # the base gets the first row from the robot
    robot.belief[19, :10] = FREE  # news the base lacks
    links = np.zeros((3, 3), dtype=bool)
    links[1, 2] = links[2, 1] = True
    run(links, 1)
    assert (other.belief[19, :10] == FREE).all() and (other.belief[0, :10] == UNKNOWN).all()
    assert (base.belief[19, :] == UNKNOWN).all()


def test_nearest_sends_the_cells_nearest_the_sender_first() -> None:
    a, b = agents = make_agents(2)
    a.position = (2.0, 19.0)
    a.belief[0, :] = FREE
    a.belief[18, :] = FREE
    Bounded(agents, capacity=20 * CELL_BYTES + record_bytes(a, 0), priority="nearest")(chain(2), 0)
    assert (b.belief[18, :] == FREE).all() and (b.belief[0, :] == UNKNOWN).all()


def test_fitting_takes_the_longest_prefix_that_fits() -> None:
    assert fitting([40, 40, 100], 100) == 2
    assert fitting([40, 40], 10_000) == 2
    assert fitting([120, 10], 100) == 0


def bounded_scenario(scenario_file: Any, **communication: Any) -> Path:
    path: Path = scenario_file(
        steps=40, communication={"model": "disk", **communication}, metrics={"columns": []}
    )
    return path


def test_an_unlimited_capacity_ends_in_the_maps_of_the_unbounded_exchange(
    scenario_file: Any,
) -> None:
    plain = Simulation.from_yaml(bounded_scenario(scenario_file))
    bounded = Simulation.from_yaml(bounded_scenario(scenario_file, capacity=10**9))
    for _ in range(40):
        plain.step()
        bounded.step()
        for x, y in zip(plain.agents, bounded.agents, strict=True):
            np.testing.assert_array_equal(x.belief, y.belief)


def test_a_small_capacity_slows_knowledge_reaching_the_base(scenario_file: Any) -> None:
    plain = Simulation.from_yaml(bounded_scenario(scenario_file))
    slow = Simulation.from_yaml(bounded_scenario(scenario_file, capacity=300))
    for _ in range(15):
        plain.step()
        slow.step()
    assert slow.known_at_base < plain.known_at_base


def test_bounded_runs_log_their_load_and_replay_recomputes_the_columns(
    scenario_file: Any, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = bounded_scenario(scenario_file, capacity=400, latency=2)
    runs = []
    for name in ("one", "two"):
        out = tmp_path / name
        assert main(["run", str(path), "--out", str(out), "--quiet", "--no-plots"]) == 0
        runs.append((out / "metrics.csv").read_bytes())
    assert runs[0] == runs[1]  # same seed, same bytes
    lines = runs[0].decode().splitlines()
    header = lines[0].split(",")
    for name in ("backlog_A", "bytes_offered", "bytes_to_base", "connected_to_base"):
        assert name in header
    offered = [int(line.split(",")[header.index("bytes_offered")]) for line in lines[1:]]
    sent = [int(line.split(",")[header.index("bytes_sent")]) for line in lines[1:]]
    assert max(offered) > 400 and all(s <= o for s, o in zip(sent, offered, strict=True))
    totals = json.loads((tmp_path / "one" / "summary.json").read_text())["communication"]
    assert totals["bytes_sent"] == sum(sent) and totals["backlog_max"] > 0
    assert 0 <= totals["connected_to_base_mean"] <= 1
    assert main(["replay", str(tmp_path / "one"), "--metrics"]) == 0
    assert "metrics.csv: DIFFERENT" not in capsys.readouterr().out


class SendsCornerFirst:
    """A strategy hook only: the cells nearest a point below the map go first."""

    def send_first(self) -> tuple[float, float] | None:
        return (19.0, 25.0)


def test_a_strategy_chosen_priority_sends_the_cells_nearest_its_point_first() -> None:
    a, b = agents = make_agents(2)
    a.position = (0.0, 0.0)
    a.belief[0, :] = FREE
    a.belief[19, :] = FREE
    a.strategy = SendsCornerFirst()  # type: ignore[attr-defined]
    capacity = 20 * CELL_BYTES + record_bytes(a, 0)
    Bounded(agents, capacity=capacity, priority="strategy")(chain(2), 0)
    assert (b.belief[19, :] == FREE).all() and (b.belief[0, :] == UNKNOWN).all()
    c, d = plain = make_agents(2)  # no strategy: base_first, nearest the sender
    c.position = (5.0, 0.0)
    c.belief[0, :] = FREE
    c.belief[19, :] = FREE
    Bounded(plain, capacity=capacity, priority="strategy")(chain(2), 0)
    assert (d.belief[0, :] == FREE).all() and (d.belief[19, :] == UNKNOWN).all()


def test_a_bounded_control_channel_carries_records_only(scenario_file: Any) -> None:
    control = {"model": "disk", "range": 500, "capacity": 100, "latency": 2}
    sim = Simulation.from_yaml(bounded_scenario(scenario_file, dropout=1.0, control=control))
    base = sim.agents[0]
    for _ in range(12):
        sim.step()
        assert sim.comm.control_traffic.cells == 0
        assert (sim.comm.control_traffic.sent <= 100).all()
    assert (base.belief == UNKNOWN).all()  # no map on the control channel
    assert {"A", "B"} <= set(base.teammates)
