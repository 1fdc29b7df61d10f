"""A robot never quits while its body fits to a frontier, and a collision never freezes it
(``strategies/relax.py``)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from mresim_phys import Simulation
from mresim_phys.strategies import Decision, RobotView, relax
from mresim_phys.strategies.base import GOAL_MET, NO_FRONTIER
from mresim_phys.strategies.frontier import FrontierExploration
from mresim_phys.strategies.params import FrontierParams
from mresim_phys.types import FREE, OCCUPIED, UNKNOWN

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"


def doorway_view(door: int, position: tuple[float, float] = (20.5, 20.5)) -> RobotView:
    """A known 40x40 room with a ``door``-cell wide passage through its 12-cell-thick east
    wall, unknown beyond; radius 1, margin 1.5 (clearance 2.5)."""
    belief = np.full((40, 80), UNKNOWN, dtype=np.uint8)
    belief[:, :50] = OCCUPIED
    belief[2:38, 2:38] = FREE
    top = 20 - door // 2
    belief[top : top + door, 38:50] = FREE
    return RobotView(
        step=10,
        name="A",
        position=position,
        heading=0.0,
        belief=belief,
        radius=1.0,
        clearance=2.5,
        speed=3.0,
        sensor_range=30.0,
        role="explorer",
        base_position=(10.5, 20.5),
        teammates={},
        rng=np.random.default_rng(0),
    )


def strategy() -> FrontierExploration:
    return FrontierExploration(FrontierParams(init_cycles=0, done_fraction=None))


def test_a_doorway_the_margin_closes_is_taken_at_a_smaller_clearance() -> None:
    """A 3-cell doorway: closed at clearance 2.5 (the strategy alone says done), open at
    the body's radius 1: the robot heads through it instead of going home."""
    view = doorway_view(3)
    alone = strategy().decide(view)
    assert alone.done and alone.info["reason"] == NO_FRONTIER
    decision = relax.decide(strategy(), view)
    assert not decision.done
    assert decision.goal is not None and decision.goal[0] > 40
    assert decision.info["clearance_reason"] == relax.RELAXED


def test_a_doorway_narrower_than_the_body_means_done() -> None:
    """A 1-cell gap: the body (radius 1) does not fit under any margin; done it is."""
    decision = relax.decide(strategy(), doorway_view(1))
    assert decision.done and decision.info["reason"] == NO_FRONTIER
    assert not relax.frontier_reachable(doorway_view(1), 1.0)
    assert relax.frontier_reachable(doorway_view(3), 1.0)


def test_a_robot_standing_where_its_margin_closes_escapes() -> None:
    """Standing 1.5 cells from a wall (its clearance 2.5 closes there and snapping does not
    reach far enough out of a long pocket): it plans out at a smaller clearance."""
    view = doorway_view(9)
    belief = view.belief.copy()
    belief[2:38, 5:38] = OCCUPIED  # a 3-cell-wide pocket along the west wall ...
    belief[2:5, 5:38] = FREE  # ... joined to a corridor along the north wall to the door
    belief[2:5, 35:38] = FREE
    belief[5:38, 35:38] = FREE
    pocket = replace(view, belief=belief, position=(3.5, 30.5))
    assert strategy().decide(pocket).done
    decision = relax.decide(strategy(), pocket)
    assert not decision.done and len(decision.path) > 0


def test_the_strategy_s_own_reason_to_go_home_is_kept() -> None:
    """The mission-complete rule is the strategy's choice: never second-guessed."""
    view = replace(doorway_view(3), free_area=10, step=500)
    params = FrontierParams(init_cycles=0, done_fraction=0.5, done_after=0)
    decision = relax.decide(FrontierExploration(params), view)
    assert decision.done and decision.info["reason"] == GOAL_MET


def test_a_collision_never_freezes_a_robot_with_no_wall_margin() -> None:
    """Library, 8 robots, wall_margin 0: a diagonal move past a wall corner its map knows
    bumps and teaches the map nothing. Before, robots bumped every step from then on (the
    team froze near 60 % explored); now no robot is in error 3 steps running."""
    sim = Simulation.from_yaml(
        SCENARIOS / "11_library_8_robots.yaml", steps=120, **{"team.wall_margin": 0.0}
    )
    run = {r.name: 0 for r in sim.robots}
    longest = 0
    for record in sim.iterate():
        for robot in record.robots:
            run[robot.name] = run[robot.name] + 1 if robot.state == "error" else 0
            longest = max(longest, run[robot.name])
    assert longest < 3
    assert record.explored > 0.72


def test_a_robot_that_reaches_its_goal_mid_step_goes_on() -> None:
    """Library, 8 robots: frontier targets are often under a step's length away. A robot
    that reaches one asks its strategy again and goes on in the same step: fewer than 7 %
    of robot-steps move under half the speed (11 % when it stood for the rest of the step)."""
    sim = Simulation.from_yaml(SCENARIOS / "11_library_8_robots.yaml", steps=120)
    before = None
    short = total = 0
    for record in sim.iterate():
        moved = np.array([r.distance for r in record.robots])
        if before is not None:
            short += int(np.count_nonzero(moved - before < 5.0))
            total += len(moved)
        before = moved
    assert short / total < 0.07


def test_a_robot_its_map_walls_in_looks_around_instead_of_quitting() -> None:
    """Its map holds walls all round it (one false: a face joined across an alcove's
    mouth) while frontiers remain beyond: it is not done; it turns to face behind it and
    scans, which clears a false wall the rays pass through."""
    view = doorway_view(9)
    belief = view.belief.copy()
    belief[18:23, 18:23] = OCCUPIED
    belief[19:22, 19:22] = FREE  # a 3x3 pocket round the robot
    boxed = replace(view, belief=belief, position=(20.5, 20.5), heading=0.0)
    assert relax.boxed_in(boxed)
    decision = relax.decide(strategy(), boxed)
    assert not decision.done and decision.info["reason"] == relax.BOXED
    assert decision.look_at is not None and decision.look_at[0] < 20.5
    assert not relax.boxed_in(view)  # the open room: done means done


def test_a_diagonal_past_a_wall_corner_goes_round_it_at_half_a_cell() -> None:
    """At clearance 0.5 (radius 0.5, no margin) a cell beside a wall is passable and a
    diagonal move between two such cells passes the wall's corner at no distance: the
    path gets a stop at the free cell of the corner, so the body never touches it."""
    belief = np.full((6, 6), FREE, dtype=np.uint8)
    belief[2, 3] = OCCUPIED
    path = np.array([[2.5, 2.5], [3.5, 1.5], [4.5, 0.5]])
    uncut = relax.uncut_corners(path, belief)
    assert uncut.tolist() == [[2.5, 2.5], [2.5, 1.5], [3.5, 1.5], [4.5, 0.5]]
    belief[2, 3] = FREE
    assert relax.uncut_corners(path, belief).tolist() == path.tolist()


def slit_view(position: tuple[float, float]) -> RobotView:
    """:func:`doorway_view`'s room with a 1-cell slit through its east wall, for a robot of
    radius 0.5 and margin 0.5: the slit opens only at the body's own clearance (0.5); a
    strip beyond is known free, its far edge a frontier."""
    view = doorway_view(1, position)
    belief = view.belief.copy()
    belief[2:38, 50:56] = FREE
    return replace(view, belief=belief, radius=0.5, clearance=1.0, speed=10.0)


def test_a_path_at_the_relaxed_half_cell_clearance_never_cuts_a_wall_corner() -> None:
    """Relaxed to its radius 0.5, a robot's plan runs beside walls, and a diagonal move
    between two cells there passes a wall corner at no distance (RAS2014-3: 39 of 83
    collisions in 700 steps). Every leg of the relaxed path keeps the body clear of every
    wall its map knows."""
    view = slit_view((30.5, 12.5))
    decision = relax.decide(strategy(), view)
    assert not decision.done and decision.info["clearance_reason"] == relax.RELAXED
    assert decision.goal is not None and decision.goal[0] > 40
    legs = zip(decision.path[:-1], decision.path[1:], strict=True)
    assert all(relax.body_clear(view.belief, tuple(a), tuple(b), 0.5) for a, b in legs)


def test_a_body_touching_a_wall_may_slide_along_it_or_leave_it_not_press_into_it() -> None:
    belief = np.full((20, 20), FREE, dtype=np.uint8)
    belief[9, :] = OCCUPIED  # a wall whose face is the line y = 10
    at = (5.5, 10.5)  # radius 0.5: touching it
    assert relax.body_clear(belief, at, (12.5, 10.5), 0.5)  # along
    assert relax.body_clear(belief, at, (8.5, 14.5), 0.5)  # away
    assert not relax.body_clear(belief, at, (8.5, 10.4), 0.5)  # into it, a little
    assert not relax.body_clear(belief, (5.5, 12.0), (5.5, 10.2), 0.5)


def test_the_random_step_after_a_bump_never_presses_into_the_wall_it_touches() -> None:
    """After a bump the robot's heading points into the wall it touches; the original's
    random step turns at most 45 degrees from it, and at the body's clearance a line that
    grazes on into the wall was taken, failed, and was drawn again (RAS2014-3: one robot
    bumped 22 steps running). The escape step keeps the body clear, on every draw."""
    belief = np.full((40, 40), FREE, dtype=np.uint8)
    belief[19, :] = OCCUPIED  # the wall above the robot
    belief[0, :] = belief[-1, :] = belief[:, 0] = belief[:, -1] = OCCUPIED
    for seed in range(20):
        view = replace(
            slit_view((20.5, 20.5)),
            belief=belief,
            heading=-3 * np.pi / 4,  # up and left, into the wall
            escaping=True,
            rng=np.random.default_rng(seed),
        )
        step = relax.decide(FrontierExploration(FrontierParams(init_cycles=0)), view)
        assert len(step.path) == 2, seed
        start, end = tuple(step.path[0]), tuple(step.path[1])
        assert relax.body_clear(belief, start, end, 0.5), (seed, end)


class SnappedStart:
    """A strategy whose path starts on a cell up-left of the robot, beyond the corner of
    the wall face it touches: where a planner snaps a start whose own cell is not
    passable at the robot's clearance."""

    params = FrontierParams()

    def decide(self, view: RobotView) -> Decision:
        path = np.array([[14.5, 17.5], [14.5, 10.5]])
        return Decision(path=path, goal=(14.5, 10.5))


def touching_view() -> RobotView:
    """A 30x30 room, a wall face at x = 15 (column 14, rows 19-28) that the robot at
    (15.5, 19.5), radius 0.5, touches; clearance 1.0."""
    belief = np.full((30, 30), FREE, dtype=np.uint8)
    belief[0, :] = belief[-1, :] = belief[:, 0] = belief[:, -1] = OCCUPIED
    belief[19:29, 14] = OCCUPIED
    return replace(doorway_view(3), belief=belief, position=(15.5, 19.5), radius=0.5,
                   clearance=1.0, base_position=(5.5, 5.5))  # fmt: skip


def test_a_snapped_start_never_leads_the_body_into_the_wall_it_touches() -> None:
    """The straight leg onto a snapped start pressed into the wall the robot touched: it
    bumped, replanned the same leg and stood in error for 277 steps (ipa_office). The
    leg is driven at the body's own clearance instead, and the path still ends where the
    strategy sent it."""
    view = touching_view()
    start, first = view.position, (14.5, 17.5)
    assert not relax.body_clear(view.belief, start, first, view.radius)
    decision = relax.decide(SnappedStart(), view)  # type: ignore[arg-type]
    path = decision.path
    assert decision.goal == (14.5, 10.5) and tuple(path[-1]) == (14.5, 10.5)
    legs = zip([start, *map(tuple, path[:-1])], map(tuple, path), strict=True)
    assert all(relax.body_clear(view.belief, a, b, view.radius) for a, b in legs)
