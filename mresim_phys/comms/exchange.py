"""Knowledge exchange (phase 6b): merge maps and teammate records along links.

Linked agents swap occupancy grids (``np.maximum``: known beats unknown, a cell
seen as obstacle by either stays obstacle), safe space (OR) and teammate
records (the newer report of each agent wins). With ``multi_hop`` (the default,
as the original closes its link table over chains) every connected group of
agents ends the step with the same knowledge; without it, each agent merges
only what its direct neighbours knew at the start of the phase.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components

from ..agents import Agent, TeammateInfo
from ..mapping import merge_into


def linked_groups(links: np.ndarray) -> list[list[int]]:
    """Connected groups (two or more agents) of the link graph, each sorted, in index order."""
    count, labels = connected_components(csr_matrix(links), directed=False)
    groups = [np.flatnonzero(labels == g).tolist() for g in range(count)]
    return sorted((g for g in groups if len(g) > 1), key=lambda g: g[0])


def newest_records(agents: Sequence[Agent], step: int) -> dict[str, TeammateInfo]:
    """Every record the agents hold plus their own, keeping the newest per agent name."""
    merged: dict[str, TeammateInfo] = {}
    for agent in agents:
        for record in (*agent.teammates.values(), agent.own_record(step)):
            held = merged.get(record.name)
            if held is None or record.step > held.step:
                merged[record.name] = record
    return merged


def share_group(agents: Sequence[Agent], step: int) -> None:
    """Give every agent of a linked group the union of the group's knowledge."""
    belief, safe = agents[0].belief.copy(), agents[0].safe.copy()
    for agent in agents[1:]:
        merge_into(belief, agent.belief)
        safe |= agent.safe
    records = newest_records(agents, step)
    for agent in agents:
        np.copyto(agent.belief, belief)
        np.copyto(agent.safe, safe)
        agent.teammates = {k: v for k, v in records.items() if k != agent.name}


def share_direct(agents: Sequence[Agent], links: np.ndarray, step: int) -> None:
    """One hop only: each agent merges what its direct neighbours knew before the phase."""
    linked = np.flatnonzero(links.any(axis=1))
    before = {i: (agents[i].belief.copy(), agents[i].safe.copy()) for i in linked}
    records = {i: newest_records([agents[i]], step) for i in linked}
    for i in linked:
        for j in np.flatnonzero(links[i]):
            merge_into(agents[i].belief, before[j][0])
            agents[i].safe |= before[j][1]
            for name, record in records[j].items():
                held = agents[i].teammates.get(name)
                if name != agents[i].name and (held is None or record.step > held.step):
                    agents[i].teammates[name] = record


def exchange(agents: Sequence[Agent], links: np.ndarray, step: int, multi_hop: bool) -> None:
    """Exchange knowledge along ``links`` (index 0 = base) and stamp base contacts."""
    if multi_hop:
        groups = linked_groups(links)
        for group in groups:
            share_group([agents[i] for i in group], step)
        reach_base = next((g for g in groups if g[0] == 0), [])
    else:
        share_direct(agents, links, step)
        reach_base = np.flatnonzero(links[0]).tolist()
    for i in reach_base:
        agents[i].last_base_contact = step
