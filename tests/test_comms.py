"""Communication: the disk model and knowledge exchange along links."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mresim_phys import COMM_MODELS
from mresim_phys.agents import Agent, empty_belief
from mresim_phys.comms.disk import DiskComm, DiskParams
from mresim_phys.comms.exchange import exchange
from mresim_phys.types import FREE, OCCUPIED, UNKNOWN


def disk_links(positions: list[tuple[float, float]], ranges: list[float]) -> np.ndarray:
    return DiskComm(DiskParams()).links(np.array(positions, float), np.array(ranges, float), None)  # type: ignore[arg-type]


def test_disk_links_when_closer_than_the_sum_of_ranges() -> None:
    links = disk_links([(0, 0), (25, 0), (60, 0)], [10, 20, 5])
    assert links[0, 1]  # 25 < 10 + 20
    assert not links[1, 2]  # 35 > 20 + 5
    assert not links[0, 2]
    assert not disk_links([(0, 0), (30, 0)], [10, 20])[0, 1]  # exactly the sum: not below it


@settings(max_examples=50, deadline=None)
@given(
    st.lists(
        st.tuples(st.floats(0, 100), st.floats(0, 100), st.floats(0, 40)), min_size=1, max_size=12
    )
)
def test_links_are_symmetric_without_self_links(agents: list[tuple[float, float, float]]) -> None:
    links = disk_links([(x, y) for x, y, _ in agents], [r for _, _, r in agents])
    assert np.array_equal(links, links.T)
    assert not links.diagonal().any()


def test_disk_is_registered_and_unknown_models_suggest_names() -> None:
    assert COMM_MODELS.get("disk") is DiskComm
    with pytest.raises(KeyError, match="disk"):
        COMM_MODELS.get("dsik")


def make_agents(n: int) -> list[Agent]:
    agents = []
    for i in range(n):
        belief, safe = empty_belief((4, 4))
        agents.append(Agent(f"a{i}", i, (float(i), 0.0), 1.0, belief, safe, "explorer"))
    return agents


def chain_links(n: int) -> np.ndarray:
    links = np.zeros((n, n), dtype=bool)
    for i in range(n - 1):
        links[i, i + 1] = links[i + 1, i] = True
    return links


def test_exchange_merges_maps_known_beats_unknown_obstacle_beats_free() -> None:
    a, b = make_agents(2)
    a.belief[0, 0], b.belief[0, 1] = FREE, FREE
    a.belief[1, 1], b.belief[1, 1] = FREE, OCCUPIED
    exchange([a, b], chain_links(2), step=3, multi_hop=True)
    for agent in (a, b):
        assert agent.belief[0, 0] == FREE and agent.belief[0, 1] == FREE
        assert agent.belief[1, 1] == OCCUPIED
        assert agent.belief[3, 3] == UNKNOWN
    assert a.teammates["a1"].step == 3 and b.teammates["a0"].position == (0.0, 0.0)


def test_multi_hop_relays_along_a_chain_in_one_step() -> None:
    agents = make_agents(3)
    agents[2].belief[2, 2] = FREE
    exchange(agents, chain_links(3), step=1, multi_hop=True)
    assert agents[0].belief[2, 2] == FREE
    assert "a2" in agents[0].teammates
    assert agents[2].last_base_contact == 1


def test_without_multi_hop_information_moves_one_link_per_step() -> None:
    agents = make_agents(3)
    agents[2].belief[2, 2] = FREE
    exchange(agents, chain_links(3), step=1, multi_hop=False)
    assert agents[0].belief[2, 2] == UNKNOWN and agents[1].belief[2, 2] == FREE
    assert "a2" not in agents[0].teammates
    exchange(agents, chain_links(3), step=2, multi_hop=False)
    assert agents[0].belief[2, 2] == FREE
    assert agents[0].teammates["a2"].step == 1


def test_no_one_learns_of_an_agent_it_was_never_linked_to() -> None:
    agents = make_agents(4)
    links = np.zeros((4, 4), dtype=bool)
    links[0, 1] = links[1, 0] = links[2, 3] = links[3, 2] = True
    exchange(agents, links, step=1, multi_hop=True)
    assert set(agents[0].teammates) == {"a1"}
    assert set(agents[3].teammates) == {"a2"}
