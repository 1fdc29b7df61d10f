"""The explorable area (world/explorable.py, world/sight.py): what a team can see from
where its bodies can go, against a brute-force definition, and followed across changes."""

from __future__ import annotations

from collections import deque

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mresim_phys.knowledge.coverage import Coverage
from mresim_phys.planning.fields import clearance_kernel
from mresim_phys.types import BoolGrid
from mresim_phys.world.explorable import (
    Explorable,
    RobotSight,
    body_kernel,
    explorable_mask,
    follow_world,
    sight_kernel,
)
from mresim_phys.world.maps import free_components_mask
from mresim_phys.world.reach import Reachable
from mresim_phys.world.sight import clear_line
from mresim_phys.world.space import World

RADII = [0.3, 0.5, 0.8, 1.0, 1.4, 2.0]
RANGES = [0.5, 1.0, 2.5, 4.0, 7.0, 30.0]


def two_rooms(door: tuple[int, int], thick: int = 2) -> BoolGrid:
    """A 40 x 60 map: outer wall, a wall of ``thick`` cells at columns 30.., a gap in it
    over rows ``door`` (start, stop)."""
    occ = np.zeros((40, 60), dtype=bool)
    occ[0, :] = occ[-1, :] = occ[:, 0] = occ[:, -1] = True
    occ[:, 30 : 30 + thick] = True
    occ[door[0] : door[1], 30 : 30 + thick] = False
    return occ


# brute force: every definition spelled out cell by cell, in doubled whole coordinates
# (cell (r, c) is the square [2c, 2c + 2] x [2r, 2r + 2], its centre (2c + 1, 2r + 1))


def brute_positions(occ: BoolGrid, radius: float) -> BoolGrid:
    """Cell centres at least ``radius`` from every occupied square and the map's outside."""
    rows, cols = occ.shape
    padded = np.pad(occ, 1, constant_values=True)
    walls = np.argwhere(padded) - 1  # (row, col), the outside ring included
    out = np.zeros(occ.shape, dtype=bool)
    for r in range(rows):
        for c in range(cols):
            gy = np.maximum(np.abs(walls[:, 0] - r) - 0.5, 0.0)
            gx = np.maximum(np.abs(walls[:, 1] - c) - 0.5, 0.0)
            out[r, c] = not (gx * gx + gy * gy < radius * radius).any()
    return out


def blocked(p: np.ndarray, q: np.ndarray, walls: np.ndarray) -> np.ndarray:
    """For segments p[i] -> q[i] (cell centres, (n, 2) row, col): whether the closed segment
    meets a closed occupied square of ``walls`` ((m, 2) row, col)."""
    y0, x0 = (2 * p[:, 0] + 1)[:, None], (2 * p[:, 1] + 1)[:, None]
    y1, x1 = (2 * q[:, 0] + 1)[:, None], (2 * q[:, 1] + 1)[:, None]
    top, left = 2 * walls[:, 0][None, :], 2 * walls[:, 1][None, :]
    apart = (np.maximum(x0, x1) < left) | (np.minimum(x0, x1) > left + 2)
    apart |= (np.maximum(y0, y1) < top) | (np.minimum(y0, y1) > top + 2)
    sides = [
        np.sign((x1 - x0) * (top + dy - y0) - (y1 - y0) * (left + dx - x0))
        for dy in (0, 2)
        for dx in (0, 2)
    ]
    one_side = np.all([s > 0 for s in sides], axis=0) | np.all([s < 0 for s in sides], axis=0)
    hit: np.ndarray = (~apart & ~one_side).any(axis=1)
    return hit


def brute_reach(occ: BoolGrid, robot: RobotSight) -> BoolGrid:
    """Positions 4-connected to the start's seeds (its cell, else neighbours in sight)."""
    rows, cols = occ.shape
    places = brute_positions(occ, robot.radius)
    row, col = int(robot.start[1]), int(robot.start[0])
    walls = np.argwhere(occ)
    near = [(row + dr, col + dc) for dr in (-1, 0, 1) for dc in (-1, 0, 1)]
    near = [(r, c) for r, c in near if 0 <= r < rows and 0 <= c < cols and places[r, c]]
    if places[row, col]:
        seeds = [(row, col)]
    else:
        here = np.array([[row, col]] * len(near)).reshape(-1, 2)
        ok = ~blocked(here, np.array(near).reshape(-1, 2), walls)
        seeds = [cell for cell, fine in zip(near, ok, strict=True) if fine]
    reach = np.zeros(occ.shape, dtype=bool)
    queue = deque(seeds)
    for cell in seeds:
        reach[cell] = True
    while queue:
        r, c = queue.popleft()
        for rr, cc in ((r + 1, c), (r - 1, c), (r, c + 1), (r, c - 1)):
            if 0 <= rr < rows and 0 <= cc < cols and places[rr, cc] and not reach[rr, cc]:
                reach[rr, cc] = True
                queue.append((rr, cc))
    return reach


def brute_explorable(occ: BoolGrid, robots: list[RobotSight]) -> BoolGrid:
    """Free cells some robot sees from some reachable position within its range."""
    out = np.zeros(occ.shape, dtype=bool)
    walls, free = np.argwhere(occ), np.argwhere(~occ)
    for robot in robots:
        for p in np.argwhere(brute_reach(occ, robot)):
            near = free[((free - p) ** 2).sum(axis=1) <= robot.sensor_range**2]
            seen = ~blocked(np.repeat(p[None, :], len(near), axis=0), near, walls)
            out[near[seen, 0], near[seen, 1]] = True
    return out


@st.composite
def maps_and_teams(draw: st.DrawFn) -> tuple[BoolGrid, list[RobotSight]]:
    """A random small map and one to three robots starting on its free cells."""
    rows, cols = draw(st.integers(3, 11)), draw(st.integers(3, 11))
    density = draw(st.sampled_from([0.05, 0.15, 0.3, 0.45]))
    seed = draw(st.integers(0, 2**32 - 1))
    occ = np.random.default_rng(seed).random((rows, cols)) < density
    free = np.argwhere(~occ)
    if len(free) == 0:
        occ[0, 0], free = False, np.array([[0, 0]])
    robots = []
    for _ in range(draw(st.integers(1, 3))):
        row, col = free[draw(st.integers(0, len(free) - 1))]
        x, y = col + draw(st.floats(0.1, 0.9)), row + draw(st.floats(0.1, 0.9))
        radius, sensor = draw(st.sampled_from(RADII)), draw(st.sampled_from(RANGES))
        robots.append(RobotSight((x, y), radius, sensor))
    return occ, robots


@settings(max_examples=150, deadline=None)
@given(case=maps_and_teams())
def test_explorable_equals_the_brute_force_definition(
    case: tuple[BoolGrid, list[RobotSight]],
) -> None:
    occ, robots = case
    assert np.array_equal(explorable_mask(occ, robots), brute_explorable(occ, robots))


@settings(max_examples=60, deadline=None)
@given(case=maps_and_teams())
def test_reachable_positions_equal_the_brute_force_ones(
    case: tuple[BoolGrid, list[RobotSight]],
) -> None:
    occ, robots = case
    explorable = Explorable(occ, robots[:1])
    assert np.array_equal(explorable.groups[0].reach, brute_reach(occ, robots[0]))


def test_a_door_narrower_than_the_body_keeps_the_room_out_but_what_is_seen_through_it() -> None:
    occ = two_rooms(door=(18, 21))  # 3 cells: a robot of radius 2 needs 4
    robot = RobotSight((10.5, 19.5), 2.0, 20.0)
    explorable = Explorable(occ, [robot])
    reach, mask = explorable.groups[0].reach, explorable.mask
    assert not reach[:, 30:].any() and reach[19, 10]
    assert mask[19, 35] and mask[19, 40]  # straight through the door, within range
    assert not mask[19, 55]  # straight through, beyond the range from every position
    assert not mask[2, 40] and not mask[37, 58]  # the far room's corners, out of sight
    assert mask[:, :30][~occ[:, :30]].all()  # all of the robot's own room
    assert free_components_mask(occ, [robot.start])[2, 40]  # connected: the old definition
    wide = Explorable(occ, [RobotSight((10.5, 19.5), 1.0, 20.0)])  # radius 1 fits through
    assert wide.groups[0].reach[19, 40] and wide.mask[2, 40]


def test_a_window_lets_a_robot_see_but_not_enter() -> None:
    occ = two_rooms(door=(20, 21), thick=3)  # a 1-cell slit through a 3-cell wall
    explorable = Explorable(occ, [RobotSight((5.5, 20.5), 1.0, 100.0)])
    beyond = explorable.mask[:, 33:59]
    assert not explorable.groups[0].reach[:, 30:].any()
    assert beyond[20, :].all()  # the row straight through the slit
    assert beyond.sum() < 0.3 * np.count_nonzero(~occ[:, 33:59])  # a fan of slope 1/3
    assert not explorable.mask[5, 50] and not explorable.mask[35, 40]


def test_robots_of_one_size_share_a_group_and_the_team_sees_the_union() -> None:
    occ = two_rooms(door=(18, 21))
    small, big = RobotSight((50.5, 19.5), 1.0, 20.0), RobotSight((10.5, 19.5), 2.0, 20.0)
    team = Explorable(occ, [big, small, RobotSight((12.5, 30.5), 2.0, 20.0)])
    assert len(team.groups) == 2 and len(team.groups[0].seeds) == 2
    alone = [explorable_mask(occ, [robot]) for robot in (big, small)]
    assert np.array_equal(team.mask, alone[0] | alone[1])


def test_a_start_too_near_a_wall_seeds_from_its_neighbours_in_sight() -> None:
    occ = np.zeros((9, 9), dtype=bool)
    occ[:, 0] = occ[:, 8] = occ[0, :] = occ[8, :] = True
    start = RobotSight((1.9, 4.5), 1.0, 3.0)  # cell (4, 1): its 3 x 3 touches the wall
    explorable = Explorable(occ, [start])
    assert explorable.robots[0].seeds == ((3, 2), (4, 2), (5, 2))
    assert explorable.groups[0].reach[4, 4]


def test_kernels_match_the_planners_and_contain_what_any_position_sees() -> None:
    for radius in [*RADII, 3.0, 4.5]:
        assert np.array_equal(body_kernel(radius), clearance_kernel(radius))
        seen = sight_kernel(radius, 100.0)
        assert not (seen & ~body_kernel(radius)).any() and seen[seen.shape[0] // 2].all()
    assert sight_kernel(2.0, 1.0).sum() == 5  # the range limits it too


def test_sight_is_blocked_by_corners_it_touches() -> None:
    occ = np.zeros((3, 3), dtype=bool)
    occ[0, 1] = True  # the diagonal from (0, 0) to (1, 1) passes through its corner
    assert not clear_line(occ, 0, 0, 1, 1) and not clear_line(occ, 1, 1, 0, 0)
    assert clear_line(occ, 0, 0, 2, 0) and clear_line(occ, 1, 0, 1, 2)
    assert not clear_line(occ, 2, 0, 0, 2)  # the long diagonal passes that corner too


def change_at(
    truth: BoolGrid, rng: np.random.Generator
) -> tuple[tuple[int, int, int, int], BoolGrid]:
    """Flip a random small box of ``truth`` in place: walls, free, or a mix."""
    rows, cols = truth.shape
    h, w = int(rng.integers(1, 5)), int(rng.integers(1, 5))
    r0, c0 = int(rng.integers(0, rows - h + 1)), int(rng.integers(0, cols - w + 1))
    box = (r0, r0 + h, c0, c0 + w)
    region = truth[r0 : r0 + h, c0 : c0 + w]
    kind = int(rng.integers(3))
    new = np.full(region.shape, kind == 0) if kind < 2 else rng.random(region.shape) < 0.5
    flips = new ^ region
    region[...] = new
    return box, flips


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), size=st.sampled_from([(12, 16), (40, 60)]))
def test_following_changes_equals_computing_afresh(seed: int, size: tuple[int, int]) -> None:
    rng = np.random.default_rng(seed)
    truth = rng.random(size) < 0.2
    free = np.argwhere(~truth)
    robots = [
        RobotSight((c + 0.5, r + 0.5), float(rng.choice(RADII)), float(rng.choice(RANGES)))
        for r, c in free[rng.integers(0, len(free), 2)]
    ]
    explorable = Explorable(truth, robots)
    for _ in range(10):
        box, flips = change_at(truth, rng)
        if not flips.any():
            continue
        before = explorable.mask.copy()
        window, held = explorable.update(truth, box, flips)
        fresh = Explorable(truth, explorable.robots)  # the same seeds, on the new truth
        assert np.array_equal(explorable.mask, fresh.mask)
        outside = np.ones(size, dtype=bool)
        outside[window[0] : window[1], window[2] : window[3]] = False
        assert np.array_equal(explorable.mask[outside], before[outside])
        assert np.array_equal(held, before[window[0] : window[1], window[2] : window[3]])


def test_a_door_that_closes_and_opens_takes_the_room_out_and_back() -> None:
    occ = two_rooms(door=(15, 25))
    world = World(occ, [])
    robots = [RobotSight((10.5, 19.5), 2.0, 25.0)]
    explorable, reachable = Explorable(world.occupied, robots), Reachable(occ, [(10.5, 19.5)])
    coverage = Coverage(explorable.mask, reachable.mask)
    coverage.add_cells(~occ, 0, 0)  # the team has seen every free cell
    first = coverage.total
    closed = world.set_cells((15, 25, 30, 32), True)
    follow_world(coverage, reachable, explorable, world.occupied, [closed])
    left_room = np.count_nonzero(~world.occupied[:, :30])
    assert coverage.total == coverage.total_connected == coverage.count == left_room
    opened = world.set_cells((15, 25, 30, 32), False)
    follow_world(coverage, reachable, explorable, world.occupied, [opened])
    assert coverage.total == first and coverage.count == np.count_nonzero(explorable.mask)
    assert np.array_equal(explorable.mask, explorable_mask(occ, robots))


@pytest.mark.parametrize("radius", [0.5, 2.0])
def test_a_walker_moving_along_a_corridor_is_followed_locally(radius: float) -> None:
    occ = two_rooms(door=(15, 25))
    explorable = Explorable(occ.copy(), [RobotSight((10.5, 8.5), radius, 25.0)])
    truth = occ.copy()
    for x in range(5, 20):  # short of the door, which it would close to a big robot
        box = (18, 21, x, x + 4)
        before = truth[18:21, x : x + 4].copy()
        truth[18:21, x : x + 3] = occ[18:21, x : x + 3]
        truth[18:21, x + 1 : x + 4] = True  # a 3 x 3 box one cell further along
        explorable.update(truth, box, before ^ truth[18:21, x : x + 4])
    assert explorable.relabels == 0
    assert np.array_equal(explorable.mask, Explorable(truth, explorable.robots).mask)
