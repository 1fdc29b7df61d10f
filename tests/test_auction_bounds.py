"""Phase 4 (decide): the frontier auction's lower bounds from the robot's own search.

A teammate's bid starts from lower bounds on its path costs; the auction searches for the
exact cost of a pair only when its bound could win. Bounds from the robot's own field
(the triangle inequality of path costs) rule out teammates behind walls without a search;
they must never exceed the exact cost, and the winner must not change.
"""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from test_frontiers import random_belief

import mresim_phys.strategies.auction as auction
import mresim_phys.strategies.frontier as frontier
from mresim_phys.knowledge.teammates import TeammateInfo
from mresim_phys.planning.dial import PausedSearch
from mresim_phys.planning.fields import distance_field, traversable
from mresim_phys.planning.grid import bbox
from mresim_phys.strategies import frontier_utility as fu
from mresim_phys.strategies.auction import path_bounds, straight_line
from mresim_phys.strategies.base import RobotView, plan_context
from mresim_phys.types import FREE, OCCUPIED, UNKNOWN


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), pause=st.sampled_from([3.0, 10.0, 25.0, np.inf]))
def test_bounds_never_exceed_the_teammates_exact_path_costs(seed: int, pause: float) -> None:
    passable = traversable(random_belief(seed, (40, 48)), 0.8)
    cells = np.argwhere(passable)
    box = bbox(passable)
    if len(cells) < 3 or box is None:
        return
    rng = np.random.default_rng(seed)
    me, mate, *goals = (tuple(int(v) for v in cells[i]) for i in rng.choice(len(cells), 5))
    search = PausedSearch(passable, me, box)
    search.run_below(np.inf)
    whole = search.dist.copy()
    search = PausedSearch(passable, me, box)
    search.run_below(pause)
    goals_rc = np.array(goals)
    node = search.window.node
    mine = np.array([whole[node(g)] for g in goals])
    if not np.isfinite(mine).all():
        return
    bounds = path_bounds(search, (mate[1] + 0.5, mate[0] + 0.5), mine)
    assert bounds is not None
    exact = distance_field(passable, (mate[1] + 0.5, mate[0] + 0.5)).cost_at(*goals_rc.T)
    assert (bounds <= exact).all()


@settings(max_examples=80, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    pause=st.sampled_from([3.0, 10.0, np.inf]),
    mates=st.integers(0, 10),
    searched=st.booleans(),
)
def test_teammates_bid_together_as_each_would_alone(
    seed: int, pause: float, mates: int, searched: bool
) -> None:
    """``teammate_bidders`` (all teammates' straight lines and bounds as arrays) gives each
    teammate the bid ``Bidder.estimated`` with ``path_bounds`` gives it, bit for bit: on
    passable cells, on blocked ones, off the search window, with and without a search."""
    passable = traversable(random_belief(seed, (40, 48)), 0.8)
    cells = np.argwhere(passable)
    box = bbox(passable)
    if len(cells) < 2 or box is None:
        return
    rng = np.random.default_rng(seed)
    me = tuple(int(v) for v in cells[rng.integers(len(cells))])
    goals_rc = cells[rng.choice(len(cells), 4)]
    search = PausedSearch(passable, me, box) if searched else None
    if search is not None:
        search.run_below(pause)
    mine = rng.uniform(1.0, 60.0, len(goals_rc))
    on_cells = cells[rng.choice(len(cells), mates)] + rng.uniform(0.0, 1.0, (mates, 2))
    anywhere = rng.uniform((-3.0, -3.0), (51.0, 43.0), (mates, 2))  # x, y: off the map too
    pick = rng.random(mates) < 0.5
    positions = [
        (float(a[0]), float(a[1])) if k else (float(c[1]), float(c[0]))
        for k, a, c in zip(pick, anywhere, on_cells, strict=True)
    ]
    names = [f"m{i}" for i in range(mates)]
    ranks = [int(r) for r in rng.permutation(mates)]
    together = auction.teammate_bidders(names, positions, ranks, goals_rc, search, mine)
    alone = [
        auction.Bidder.estimated(n, xy, goals_rc, r, path_bounds(search, xy, mine))
        for n, xy, r in zip(names, positions, ranks, strict=True)
    ]
    assert len(together) == len(alone)
    for a, b in zip(together, alone, strict=True):
        assert (a.name, a.position, a.rank) == (b.name, b.position, b.rank)
        assert a.costs.tobytes() == b.costs.tobytes()
        assert not a.exact.any() and a.exact.shape == b.exact.shape


def corridor_world() -> np.ndarray:
    """Two parallel corridors joined at the far east end; a frontier at the north one's
    west end."""
    belief = np.full((30, 200), OCCUPIED, dtype=np.uint8)
    belief[3:9, 2:196] = FREE  # north corridor
    belief[20:26, 2:196] = FREE  # south corridor
    belief[3:26, 190:196] = FREE  # the only link, 190 cells east
    belief[3:9, 2] = UNKNOWN
    return belief


def test_a_teammate_behind_a_wall_is_ruled_out_without_a_search(
    searched_from: list[tuple[float, float]],
) -> None:
    """The teammate stands ~17 cells from this robot's frontier, through a wall, but ~370
    cells away by path: its straight-line bound beat this robot's own bid and cost a
    search; the triangle bound does not, and the robot still wins that frontier. (Where
    its own search has paused short of the teammate, the bound is weaker: ``path_bounds``.)"""
    belief = corridor_world()
    mate = TeammateInfo("B", (8.5, 22.5), None, "active", role="explorer", step=10)
    view = RobotView(
        step=10, name="A", position=(30.5, 5.5), heading=0.0, belief=belief, radius=0.5,
        clearance=1.0, speed=2.0, sensor_range=40.0, role="explorer",
        base_position=(30.5, 5.5), teammates={"B": mate}, rng=np.random.default_rng(0),
    )  # fmt: skip
    params = frontier.FrontierParams(horizon=10.0)  # its first search settles both robots
    decision = frontier.FrontierExploration(params).decide(view)
    assert decision.goal is not None and decision.goal[1] < 10  # its own, north corridor
    context = plan_context(view)
    north = np.array([[5, 4]])
    assert straight_line(mate.position, north)[0] < 20
    bounds = path_bounds(context.search, mate.position, context.field.cost_at(*north.T))
    assert bounds is not None and bounds[0] > 300
    assert mate.position not in searched_from


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10_000), bidders=st.integers(1, 40), goals=st.integers(1, 300))
def test_the_upper_bounds_utilities_are_those_of_the_exact_costs(
    seed: int, bidders: int, goals: int
) -> None:
    """The auction's first utilities of the upper bounds are utility(high) exactly: the
    exact pairs' utilities, and -inf where a pair has no upper bound yet."""
    rng = np.random.default_rng(seed)
    costs = rng.uniform(0.0, 3000.0, (bidders, goals)) * rng.choice([1.0, np.sqrt(2)], goals)
    costs[rng.random((bidders, goals)) < 0.1] = np.inf
    exact = rng.random((bidders, goals)) < 0.5
    sizes = rng.integers(1, 400, goals).astype(np.float64)
    team = [auction.Bidder(f"R{i}", costs[i], exact[i], (0.5, 0.5), i) for i in range(bidders)]
    bids = auction.Bids.of(team, sizes)
    expected = fu.utility(sizes[None, :], np.where(exact, costs, np.inf))
    np.testing.assert_array_equal(bids.u_low, expected)
    assert bids.u_low.tobytes() == expected.tobytes()


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10_000), size=st.integers(1, 5000))
def test_a_rescored_column_holds_the_floats_utility_gives(seed: int, size: int) -> None:
    """A refinement rescores a column of the bids in one compiled pass; its utilities are
    utility()'s floats, byte for byte (ties between bids are decided on them)."""
    rng = np.random.default_rng(seed)
    costs = np.concatenate(
        (rng.uniform(0.0, 12.0, 64), rng.uniform(1.0, 6000.0, 256),
         rng.integers(0, 3000, 64) + rng.integers(0, 2000, 64) * np.sqrt(2), [np.inf, 0.0])
    )  # fmt: skip
    grid = np.stack((costs, costs[::-1], costs * 1.5), axis=1)  # a column is a strided view
    u, u_low = np.zeros_like(grid), np.zeros_like(grid)
    fu.pair_utilities(float(size), grid[:, 0], grid[:, 2], u[:, 1], u_low[:, 1])
    sizes = np.array([float(size)])
    assert u[:, 1].tobytes() == fu.utility(sizes, grid[:, 0]).tobytes()
    assert u_low[:, 1].tobytes() == fu.utility(sizes, grid[:, 2]).tobytes()


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10_000), power=st.integers(1, 4))
def test_utilities_are_the_c_librarys_pow_on_every_machine(seed: int, power: int) -> None:
    """``utility`` gives, pair by pair, the floats of ``size * 1e8 / max(d, 1) ** power`` in
    Python (the C library's ``pow``), broadcast as numpy would. numpy's ``**`` did not on a
    processor with AVX-512 (4,660 of 100,000 distances differed in the last bit), so one
    run chose other frontiers on other machines."""
    rng = np.random.default_rng(seed)
    costs = np.concatenate((rng.uniform(0.0, 400.0, (3, 60)), [[np.inf] * 60]))
    sizes = rng.integers(1, 5000, 60).astype(float)
    got = fu.utility(sizes[None, :], costs, power)
    expected = [
        [s * fu.UTILITY_SCALE / max(c, 1.0) ** float(power) if np.isfinite(c) else -np.inf
         for s, c in zip(sizes.tolist(), row, strict=True)]
        for row in costs.tolist()
    ]  # fmt: skip
    assert got.shape == costs.shape and got.tobytes() == np.array(expected).tobytes()
