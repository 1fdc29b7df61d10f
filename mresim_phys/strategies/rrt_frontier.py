"""``rrt_frontier`` (phase 4, decide): frontiers found by rapidly-exploring random trees.

After H. Umari and S. Mukhopadhyay, "Autonomous robotic exploration based on multiple
rapidly-exploring randomized trees" (IROS 2017). The robot grows two trees over the free
cells of its own map: a *global* tree, kept from decision to decision and grown from every
node it has, and a *local* tree, grown afresh from where the robot stands at each decision
(so frontiers near it are found quickly). Each step of a tree draws a point uniformly over
the map's known box (from the robot's own stream), takes the tree's nearest node and
steers ``eta`` cells towards the point: a step that crosses a wall is dropped, one that
reaches an unknown cell marks that cell a *detected frontier point* (and grows no node),
any other adds a node. The robot then explores as ``frontier`` does, but only frontier
cells within ``detect_radius`` of a point its trees detected (and still frontier) count:
frontiers no tree has reached are not known to it. With none detected it goes home, and
tries again at its next decision.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import ClassVar

import numpy as np

from mresim_phys.knowledge.frontiers import Frontiers
from mresim_phys.strategies.base import RobotView
from mresim_phys.strategies.baselines import keep_cells
from mresim_phys.strategies.catalog import STRATEGIES
from mresim_phys.strategies.frontier import FrontierExploration, default_parts
from mresim_phys.strategies.params import RRTFrontierParams, StrategyParams
from mresim_phys.types import FREE, OCCUPIED, BeliefGrid, FloatArray

Point = tuple[float, float]


@dataclass
class Trees:
    """A robot's global tree (its nodes, kept) and the frontier points its trees detected."""

    nodes: list[Point] = field(default_factory=list)
    detected: list[Point] = field(default_factory=list)


def step_towards(belief: BeliefGrid, start: Point, goal: Point, eta: float) -> tuple[str, Point]:
    """Steer ``eta`` cells from ``start`` towards ``goal`` through ``belief``:
    (``wall``, _), (``frontier``, the first unknown cell's centre) or (``node``, the end)."""
    dx, dy = goal[0] - start[0], goal[1] - start[1]
    gap = math.hypot(dx, dy)
    if gap <= 1e-9:
        return "wall", start
    share = min(1.0, eta / gap)
    end = (start[0] + share * dx, start[1] + share * dy)
    count = math.ceil(share * gap * 2) + 1
    rows, cols = belief.shape
    for k in range(1, count + 1):
        x = start[0] + (end[0] - start[0]) * k / count
        y = start[1] + (end[1] - start[1]) * k / count
        r, c = math.floor(y), math.floor(x)
        if not (0 <= r < rows and 0 <= c < cols) or belief[r, c] == OCCUPIED:
            return "wall", end
        if belief[r, c] != FREE:
            return "frontier", (c + 0.5, r + 0.5)
    return "node", end


def grow(
    belief: BeliefGrid, nodes: list[Point], steps: int, eta: float, rng: np.random.Generator
) -> list[Point]:
    """Grow the tree of ``nodes`` (in place) by ``steps`` draws; the frontier points found."""
    rows, cols = np.nonzero(belief == FREE)
    if len(rows) == 0 or not nodes:
        return []
    low, high = (
        (float(cols.min()), float(rows.min())),
        (float(cols.max()) + 1, float(rows.max()) + 1),
    )
    found: list[Point] = []
    for _ in range(steps):
        goal = (float(rng.uniform(low[0], high[0])), float(rng.uniform(low[1], high[1])))
        at = np.asarray(nodes)
        nearest = int(np.argmin((at[:, 0] - goal[0]) ** 2 + (at[:, 1] - goal[1]) ** 2))
        kind, point = step_towards(belief, nodes[nearest], goal, eta)
        if kind == "node":
            nodes.append(point)
        elif kind == "frontier":
            found.append(point)
    return found


@dataclass
class RRTDetected:
    """The frontier cells near a point the robot's trees detected (module docstring)."""

    params: RRTFrontierParams
    trees: Trees = field(default_factory=Trees)

    def keep(self, view: RobotView, found: Frontiers) -> Frontiers:
        """Grow both trees, then keep the frontier cells near a detected point."""
        p = self.params
        if not self.trees.nodes:
            self.trees.nodes.append(view.position)
        points = grow(view.belief, self.trees.nodes, p.global_steps, p.eta, view.rng)
        local = [view.position]
        points += grow(view.belief, local, p.local_steps, p.eta, view.rng)
        self.trees.detected = still_frontier([*self.trees.detected, *points], found, p)
        if len(found) == 0 or not self.trees.detected:
            return keep_cells(found, np.zeros(len(found.cells_rc), dtype=bool))
        return keep_cells(found, near(found, self.trees.detected, p.detect_radius))


def near(found: Frontiers, points: list[Point], radius: float) -> np.ndarray:
    """Which frontier cells lie within ``radius`` of one of ``points``."""
    cells = found.cells_rc.astype(float) + 0.5
    at = np.asarray(points)
    gaps = np.hypot(cells[:, None, 1] - at[None, :, 0], cells[:, None, 0] - at[None, :, 1])
    kept: np.ndarray = (gaps <= radius).any(axis=1)
    return kept


def still_frontier(points: list[Point], found: Frontiers, p: RRTFrontierParams) -> list[Point]:
    """The detected points with a frontier cell still within ``detect_radius``."""
    if not points or len(found) == 0:
        return []
    at = np.asarray(points)
    cells: FloatArray = found.cells_rc.astype(float) + 0.5
    gaps = np.hypot(at[:, None, 0] - cells[None, :, 1], at[:, None, 1] - cells[None, :, 0])
    live = (gaps <= p.detect_radius).any(axis=1)
    return [points[i] for i in np.flatnonzero(live).tolist()][-p.max_points :]


@STRATEGIES.register
class RRTFrontier(FrontierExploration):
    """Frontier exploration over the frontiers its random trees detect (Umari 2017)."""

    name = "rrt_frontier"
    Params: ClassVar[type[StrategyParams]] = RRTFrontierParams

    def __init__(self, params: RRTFrontierParams) -> None:
        self.detector = RRTDetected(params)
        super().__init__(params, replace(default_parts(params), filter=self.detector))
