"""``leader_follower`` (phase 4, decide): a chain of robots, each kept in its parent's range.

The original's ``LeaderFollower`` (after H. G. Nguyen et al., "Autonomous communication
relays for tactical robots", ICAR 2003/2004). The team's hierarchy (``parent:`` of each
robot) forms chains from the base: a robot with children is a *follower* (a relay), a
robot without is the *leader* (the explorer) at the chain's end.

* The leader explores as ``frontier`` does, among the frontiers within
  ``comm_range * hops - 5`` cells of the base (``hops``: robots from the base down to
  it), as the original does.
* A follower heads for its child's last reported position.
* Every robot decides once every step (``replan_interval: 1``, and no second decision
  within a step on reaching its goal; the leader searches frontiers again every
  ``frontier_interval`` steps and plans to its chosen one in between) and
  keeps only the part of its path within ``comm_range - speed`` of its parent's last
  known position (the base's, or the parent robot's record), so no step takes it out of
  its parent's range while the parent stands.
* A robot whose parent was not linked at the last exchange steps back to where it last
  was linked (the original: to its previous position) until the link holds again.
* A frontier the leader cannot approach without leaving its parent's range (the chain is
  stretched along the way there) is given up, and it searches again.

Distances are straight lines to the parent, as in the original; with ``path_loss`` the
range is only an estimate and the step-back rule mends the chain.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import ClassVar

import numpy as np

from mresim_phys.knowledge.frontiers import Frontiers
from mresim_phys.strategies.appointments import Appointment
from mresim_phys.strategies.base import Decision, PlanContext, RobotView, heading_for, plan_context
from mresim_phys.strategies.catalog import STRATEGIES
from mresim_phys.strategies.frontier import FrontierExploration, default_parts
from mresim_phys.strategies.params import LeaderFollowerParams, StrategyParams
from mresim_phys.types import FloatArray

LEADER_MARGIN = 5.0  # cells: the original's frontier radius is comm_range * hops - 5
STEP_BACK_WAIT = 10  # steps past its expected arrival that a step back is kept (rendezvous.md)


@STRATEGIES.register
class LeaderFollower(FrontierExploration):
    """The leader explores within the chain's reach; followers follow; nobody leaves its parent."""

    name = "leader_follower"
    Params: ClassVar[type[StrategyParams]] = LeaderFollowerParams
    # its paths are cut at its parent's range as of the last exchange: a second decision
    # within a step (motion's mid-step replan) sees the same cut, so the leader gave up
    # every frontier of a stretched chain one after the other and parked (scenario 22)
    ONE_DECISION_PER_STEP: ClassVar[bool] = True
    params: LeaderFollowerParams

    def __init__(self, params: LeaderFollowerParams) -> None:
        super().__init__(params, replace(default_parts(params), filter=ChainReach()))
        self._linked_at: tuple[float, float] | None = None  # where its parent was last linked
        self._goal: tuple[int, int] | None = None  # the leader's frontier target (row, col)
        self._searched = -(10**9)  # step of the leader's last frontier search
        self._back: Appointment | None = None  # a step back under way: meeting its parent

    def appointments(self) -> tuple[Appointment, ...]:
        """A step back under way: a meeting with its parent where the link last held, at
        its expected arrival (straight line over speed); any link with the parent from
        setting out to :data:`STEP_BACK_WAIT` steps past the arrival keeps it."""
        return () if self._back is None else (self._back,)

    def decide(self, view: RobotView) -> Decision:
        """Step back to the parent's range, follow the child, or explore within the chain."""
        context = plan_context(view)
        if view.parent is not None and view.parent not in view.links and view.step > 0:
            return self._step_back(view, context)
        self._linked_at, self._back = view.position, None
        follows = bool(view.children)
        decision = self._follow(view, context) if follows else self._lead(view, context)
        path = self._within_parent_range(view, decision.path)
        if not follows and len(decision.path) > 1 and len(path) <= 1:  # no way on
            self._out_of_reach()
        held = follows and len(path) <= 1  # at its parent's range's edge: it waits there
        return Decision(
            path=path,
            goal=view.position if held else decision.goal,
            done=decision.done,
            look_at=decision.look_at,
            info=decision.info,
        )

    def _lead(self, view: RobotView, context: PlanContext) -> Decision:
        """Greedy frontier exploration among the frontiers the chain reaches."""
        due = view.step - self._searched >= self.params.frontier_interval
        if self._goal is None or due or view.reached_goal or view.bumped:
            self._searched = view.step
            decision = super().decide(view)
            goal = decision.goal
            self._goal = None if goal is None or decision.done else _cell(goal)
            return decision
        row, col = self._goal
        path = context.plan_to(row, col)
        if len(path) == 0:
            self._goal = None  # search again at the next decision
        return Decision(path=path, goal=(col + 0.5, row + 0.5))

    def _out_of_reach(self) -> None:
        """The leader's frontier lies beyond its parent's range along its path: give up
        that frontier (its cells) and search again at the next decision."""
        if self._chasing is not None and self._tried is not None:
            rows, cols = self._chasing[:, 0], self._chasing[:, 1]
            self._tried.give_up(rows, cols)
        self._goal, self._searched = None, -(10**9)

    def _follow(self, view: RobotView, context: PlanContext) -> Decision:
        """Head for the child's last reported position (the nearest first, by name)."""
        records = [view.teammates[c] for c in view.children if c in view.teammates]
        if not records:
            return Decision(goal=view.position)
        child = min(records, key=lambda r: (math.dist(r.position, view.position), r.name))
        return heading_for(context, child.position, info={"following": child.name})

    def _step_back(self, view: RobotView, context: PlanContext) -> Decision:
        """Out of the parent's reach: back to where the link last held (else towards the
        parent's last known position)."""
        target = self._linked_at or self._parent_position(view)
        if self._back is None:
            step = view.step + math.ceil(math.dist(view.position, target) / view.speed)
            point = (float(target[0]), float(target[1]))
            closes = step + STEP_BACK_WAIT
            self._back = Appointment(view.parent or "", point, step, closes, opens=view.step)
        return heading_for(context, target, info={"stepping_back": True})

    def _parent_position(self, view: RobotView) -> tuple[float, float]:
        """The parent's last known position: the base's, or its record's (else here)."""
        if view.parent == "base":
            return view.base_position
        record = view.teammates.get(view.parent or "")
        return record.position if record is not None else view.position

    def _within_parent_range(self, view: RobotView, path: FloatArray) -> FloatArray:
        """The path's first points that stay within ``comm_range - speed`` of the parent."""
        if view.parent is None or len(path) == 0:
            return path
        keep = view.comm_range - view.speed
        parent = np.asarray(self._parent_position(view))
        inside = np.hypot(*(path - parent).T) <= keep
        stop = int(np.argmin(inside)) if not inside.all() else len(path)
        kept: FloatArray = path[:stop]
        return kept


class ChainReach:
    """The leader's frontiers, less those beyond the chain's reach from the base."""

    def keep(self, view: RobotView, found: Frontiers) -> Frontiers:
        """The clusters with a cell within the chain's reach (all of them without a chain)."""
        if view.hops <= 0 or len(found) == 0:
            return found
        radius = view.comm_range * view.hops - LEADER_MARGIN
        x, y = view.base_position
        cells = found.cells_rc
        near = np.hypot(cells[:, 1] + 0.5 - x, cells[:, 0] + 0.5 - y) <= radius
        return _keep_clusters(found, near)


def _cell(point: tuple[float, float]) -> tuple[int, int]:
    """(row, col) of the cell holding world point (x, y)."""
    return math.floor(point[1]), math.floor(point[0])


def _keep_clusters(found: Frontiers, cells_kept: np.ndarray) -> Frontiers:
    """The clusters with at least one kept cell, renumbered in their order."""
    kept = np.zeros(len(found), dtype=bool)
    kept[found.cluster_of[cells_kept]] = True
    new_index = np.cumsum(kept) - 1
    rows = kept[found.cluster_of]
    return Frontiers(
        sizes=found.sizes[kept],
        centroids=found.centroids[kept],
        cells_rc=found.cells_rc[rows],
        cluster_of=new_index[found.cluster_of[rows]],
    )
