"""The baselines papers compare against (``strategies/baselines.py``): uncoordinated nearest
frontier goes to the nearest frontier whatever its teammates do; Voronoi partitioning
never takes a frontier in a living teammate's cell, and takes over a dead robot's cell."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mresim_phys import Simulation
from mresim_phys.agents import Robot
from mresim_phys.strategies import Decision, RobotView
from mresim_phys.strategies.base import plan_context
from mresim_phys.strategies.parts import auction_team

ROOMS = Path(__file__).resolve().parent.parent / "scenarios" / "13_rooms_4_robots.yaml"


def watch(robot: Robot, sim: Simulation, seen: list[tuple[int, RobotView, Decision]]) -> None:
    """Record every decision of ``robot`` with the view it was made from."""
    strategy: Any = robot.strategy
    decide = strategy.decide

    def recorded(view: RobotView) -> Decision:
        decision: Decision = decide(view)
        seen.append((sim.t, view, decision))
        return decision

    strategy.decide = recorded


def first_target(strategy: str) -> dict[str, tuple[float, float]]:
    """The centroid of each robot's first frontier on the rooms map (no random steps)."""
    sim = Simulation.from_yaml(
        ROOMS, steps=1, **{"team.strategy": {"name": strategy, "params": {"init_cycles": 0}}}
    )
    sim.step()
    out = {}
    for robot in sim.robots:
        assert robot.decision is not None
        info = robot.decision.info
        centre = info["frontiers"].centroids[info["target_cluster"]]
        out[robot.name] = (round(float(centre[0]), 1), round(float(centre[1]), 1))
    return out


def test_nearest_frontier_takes_the_nearest_frontier_whatever_the_team_does() -> None:
    sim = Simulation.from_yaml(ROOMS, steps=60, **{"team.strategy": "nearest_frontier"})
    seen: list[tuple[int, RobotView, Decision]] = []
    watch(sim.robot("A"), sim, seen)
    sim.run()
    checked = 0
    for _, view, decision in seen:
        frontiers = decision.info.get("frontiers")
        if frontiers is None or decision.goal is None:
            continue
        field = plan_context(view).field
        costs = field.cost_at(frontiers.cells_rc[:, 0], frontiers.cells_rc[:, 1])
        goal = (math.floor(decision.goal[1]), math.floor(decision.goal[0]))
        mine = field.cost_at(np.array([goal[0]]), np.array([goal[1]]))[0]
        assert (
            mine <= np.nanmin(np.where(np.isfinite(costs), costs, np.nan)) + 3.0
        )  # its target's reach
        checked += 1
    assert checked >= 3
    # robots side by side head for the same frontier: no coordination
    goals = first_target("nearest_frontier")
    assert goals["A"] == goals["B"]
    assert len(set(first_target("frontier").values())) > 1


def voronoi_violations(seen: list[tuple[int, RobotView, Decision]], name: str) -> int:
    """Decisions whose goal frontier cell is nearer to a living known teammate."""
    bad = 0
    for _, view, decision in seen:
        frontiers = decision.info.get("frontiers")
        if frontiers is None or decision.goal is None:
            continue
        cells = frontiers.cells_rc[frontiers.cluster_of == decision.info["target_cluster"]]
        x, y = view.position
        for mate in auction_team(view, 500):
            mx, my = mate.position
            mine = np.hypot(cells[:, 1] + 0.5 - x, cells[:, 0] + 0.5 - y)
            theirs = np.hypot(cells[:, 1] + 0.5 - mx, cells[:, 0] + 0.5 - my)
            bad += int((theirs < mine).any())
    return bad


def test_voronoi_never_takes_a_frontier_in_a_living_teammates_cell() -> None:
    sim = Simulation.from_yaml(ROOMS, steps=150, **{"team.strategy": "voronoi"})
    seen = {r.name: [] for r in sim.robots}  # type: ignore[var-annotated]
    for robot in sim.robots:
        watch(robot, sim, seen[robot.name])
    sim.run()
    assert sum(len(s) for s in seen.values()) >= 20
    for name, decisions in seen.items():
        assert voronoi_violations(decisions, name) == 0, name


def test_voronoi_takes_over_a_dead_robots_cell() -> None:
    """D fails early: once it is presumed lost, its cell (the frontier nearest its last
    position) is taken by a teammate; while it lived, nobody took a frontier nearer to it."""
    events = [{"step": 20, "fail": "D"}]
    sim = Simulation.from_yaml(
        ROOMS,
        steps=400,
        events=events,
        **{"team.strategy": "voronoi", "simulation.presume_lost_after": 30},
    )
    seen = {r.name: [] for r in sim.robots}  # type: ignore[var-annotated]
    for robot in sim.robots:
        watch(robot, sim, seen[robot.name])
    sim.run()
    last = sim.base.teammates["D"].position
    took_over = 0
    for name, decisions in seen.items():
        if name == "D":
            continue
        for _step, view, decision in decisions:
            if decision.goal is None or "D" not in view.lost:
                continue
            gx, gy = decision.goal
            if math.hypot(gx - last[0], gy - last[1]) < math.hypot(
                gx - view.position[0], gy - view.position[1]
            ):
                took_over += 1
    assert took_over >= 1
    assert sim.record.explored >= 0.9


@pytest.mark.parametrize(
    "strategy", ["nearest_frontier", "voronoi", "potential_field", "periodic_return"]
)
def test_the_baselines_explore_the_rooms(strategy: str) -> None:
    sim = Simulation.from_yaml(ROOMS, **{"team.strategy": strategy})
    record = sim.run()
    assert sim.stop_reason() == "known_at_base" and record.explored > 0.9


OFFICE = ROOMS.parent / "02_office_frontier.yaml"


def test_range_constrained_never_targets_a_frontier_out_of_the_bases_reach() -> None:
    strategy = {"name": "range_constrained", "params": {"range": 150}}
    sim = Simulation.from_yaml(OFFICE, steps=300, **{"team.strategy": strategy})
    seen: list[tuple[int, RobotView, Decision]] = []
    watch(sim.robot("A"), sim, seen)
    sim.run()
    base = sim.base.position
    targets = [d for _, _, d in seen if "target_cluster" in d.info]
    assert len(targets) >= 5
    for decision in targets:
        frontiers = decision.info["frontiers"]
        cells = frontiers.cells_rc[frontiers.cluster_of == decision.info["target_cluster"]]
        far = np.hypot(cells[:, 1] + 0.5 - base[0], cells[:, 0] + 0.5 - base[1])
        assert far.max() <= 150.0
    free = Simulation.from_yaml(OFFICE, steps=300)  # frontier goes beyond it
    free.run()
    assert max(math.dist(r.position, base) for r in free.robots) > 150.0


def test_periodic_return_reports_to_the_base_every_period() -> None:
    period = 40
    overrides = {
        "team.strategy": {"name": "periodic_return", "params": {"period": period}},
        "team.comm_range": 60,
        "base_station.comm_range": 60,
    }
    sim = Simulation.from_yaml(OFFICE, steps=400, **overrides)
    seen: list[tuple[int, RobotView, Decision]] = []
    watch(sim.robot("B"), sim, seen)
    sim.run()
    due = [(view, d) for _, view, d in seen if view.step - view.base_contact >= period]
    assert len(due) >= 2
    base = sim.base.position
    for view, decision in due:
        assert decision.info.get("reason") == "periodic report"
        assert decision.goal is not None
        assert math.dist(decision.goal, base) < math.dist(view.position, base)
    explored = [d for _, view, d in seen if view.step - view.base_contact < period]
    assert any("target_cluster" in d.info for d in explored)  # it explores between reports


def test_potential_field_is_pushed_off_a_frontier_a_teammate_stands_by(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Two frontiers, the first twice as attractive; a teammate beside it repels the robot
    to the second, and with no repulsion it takes the first."""
    from types import SimpleNamespace

    from mresim_phys.knowledge.frontiers import Frontiers
    from mresim_phys.strategies import baselines
    from mresim_phys.strategies.parts import Offer

    frontiers = Frontiers(
        sizes=np.array([20, 10]), centroids=np.zeros((2, 2)),
        cells_rc=np.array([[10, 10], [10, 90]]), cluster_of=np.array([0, 1]),
    )  # fmt: skip
    view = SimpleNamespace(sensor_range=100.0)
    offer = Offer(view, None, frontiers, np.array([[10, 10], [10, 90]]),  # type: ignore[arg-type]
                  np.array([10.0, 10.0]), np.array([0, 1]))  # fmt: skip
    mate = SimpleNamespace(position=(12.0, 12.0))
    monkeypatch.setattr(baselines, "auction_team", lambda view, memory: [mate])
    assert baselines.PotentialChoice(None, 1.0, 500).choose(offer) == 1
    assert baselines.PotentialChoice(None, 0.0, 500).choose(offer) == 0
    monkeypatch.setattr(baselines, "auction_team", lambda view, memory: [])
    assert baselines.PotentialChoice(None, 1.0, 500).choose(offer) == 0


def test_an_rrt_step_stops_at_walls_and_marks_the_first_unknown_cell() -> None:
    from mresim_phys.strategies.rrt_frontier import step_towards
    from mresim_phys.types import FREE, OCCUPIED, UNKNOWN

    belief = np.full((10, 30), FREE, dtype=np.uint8)
    belief[:, 12] = OCCUPIED
    belief[:, 25:] = UNKNOWN
    assert step_towards(belief, (2.5, 5.5), (20.5, 5.5), 15.0)[0] == "wall"
    assert step_towards(belief, (14.5, 5.5), (29.5, 5.5), 15.0) == ("frontier", (25.5, 5.5))
    kind, end = step_towards(belief, (14.5, 5.5), (29.5, 5.5), 5.0)
    assert kind == "node" and end == pytest.approx((19.5, 5.5))


def test_rrt_frontier_targets_only_frontiers_its_trees_detected() -> None:
    sim = Simulation.from_yaml(ROOMS, steps=80, **{"team.strategy": "rrt_frontier"})
    robot = sim.robot("A")
    strategy: Any = robot.strategy
    decide = strategy.decide
    checked = []

    def recorded(view: RobotView) -> Decision:
        decision: Decision = decide(view)
        if "target_cluster" in decision.info:
            frontiers = decision.info["frontiers"]
            cells = frontiers.cells_rc[frontiers.cluster_of == decision.info["target_cluster"]]
            points = np.asarray(strategy.detector.trees.detected)
            gaps = np.hypot(
                cells[:, None, 1] + 0.5 - points[None, :, 0],
                cells[:, None, 0] + 0.5 - points[None, :, 1],
            )
            checked.append(bool((gaps <= strategy.params.detect_radius).any()))
        return decision

    strategy.decide = recorded
    sim.run()
    assert len(checked) >= 3 and all(checked)
    nodes = np.array([(int(y), int(x)) for x, y in strategy.detector.trees.nodes])
    assert len(nodes) > 50
    assert (robot.belief[nodes[:, 0], nodes[:, 1]] == 1).all()  # FREE: on known free cells
    assert sim.record.explored > 0.5
