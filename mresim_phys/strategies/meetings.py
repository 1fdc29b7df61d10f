"""Meetings (phase 4, decide): where and when an explorer and its relay meet next.

The rendezvous part of ``role_based`` (and ``role_switch``): :class:`Rendezvous`, the
agreement an explorer sends its relay, and :class:`MeetingPlanner`, which makes one from
the explorer's frontier: ``basic`` (the frontier target, else where it stands),
``improved`` (the best skeleton junction near the frontier: :func:`improved_point`) or
``multi_point`` (the relay's own point, linked with the explorer's through walls, and a
backup meeting: ``strategies/rendezvous.py``). The times follow the original's rules
(``role_based``'s docstring).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from mresim_phys.knowledge.teammates import Payload
from mresim_phys.strategies.base import Decision, RobotView, plan_context
from mresim_phys.strategies.rendezvous import MultiPoint, relay_point
from mresim_phys.types import FloatArray

MIN_RV_DISTANCE = 25.0  # cells: a nearer frontier is no meeting point (the original's 25 px)
IMPROVED_REACH = 600.0  # cells: junctions farther from the frontier are no candidates
IMPROVED_CANDIDATES = 4  # the nearest junctions scored (the original's 4)
MIN_MEETING_DELAY = 60  # steps: the earliest meeting after an agreement (the original)
EXPLORE_TIME = 75  # steps the explorer gets at its frontier (FRONTIER_MIN_EXPLORE_TIME)
RV_REPLAN_INTERVAL = 15  # steps: multi-point points are recomputed at most this often


@dataclass(frozen=True)
class Rendezvous(Payload):
    """An explorer's agreement with its relay: where and when they meet next.

    ``point`` is the explorer's; ``relay_point`` the relay's when they differ (multi-point:
    linked through walls); ``backup`` the meeting both fall back to when the other has
    not come by the end of the wait (multi-point). Unset fields cost no bytes."""

    point: tuple[float, float]
    step: int
    relay_point: tuple[float, float] | None = None
    backup: Rendezvous | None = None

    @property
    def relay_at(self) -> tuple[float, float]:
        """Where the relay waits."""
        return self.point if self.relay_point is None else self.relay_point

    def points(self) -> FloatArray:
        """The agreed points (explorer's, relay's, backup's) as (k, 2), for the layers."""
        pts = [self.point, self.relay_at] + ([self.backup.point] if self.backup else [])
        return np.array(pts, dtype=float)


@dataclass
class MeetingPlanner:
    """The rendezvous part: the next meeting an explorer proposes to its relay, by ``rule``
    (``basic``, ``improved`` or ``multi_point``), with ``wait`` steps of waiting at the
    point; it keeps its last multi-point choice (``multi``) for the layers and for
    :data:`RV_REPLAN_INTERVAL` steps."""

    rule: Literal["basic", "improved", "multi_point"]
    wait: int
    multi: tuple[int, MultiPoint] | None = None  # (step, last multi-point choice)

    def agree(self, view: RobotView, relay: str, explored: Decision) -> Rendezvous:
        """The next meeting: its frontier target (else here), at the original's time."""
        frontier = view.position if explored.done or explored.goal is None else explored.goal
        near = math.dist(frontier, view.position) <= MIN_RV_DISTANCE
        point = view.position if near else frontier
        if self.rule in ("improved", "multi_point") and not near:
            point = improved_point(view, frontier) or point
        point = (float(point[0]), float(point[1]))
        multi = self.rule == "multi_point"
        theirs = self.relay_point(view, point) if multi else point
        record = view.teammates.get(relay)
        relay_at = record.position if record is not None else view.position
        base = view.base_position
        relay_trip = math.dist(relay_at, base) + math.dist(base, theirs)
        own_trip = math.dist(view.position, frontier) + math.dist(frontier, point)
        delay = max(
            MIN_MEETING_DELAY, relay_trip / view.speed, own_trip / view.speed + EXPLORE_TIME
        )
        step = view.step + math.ceil(delay)
        if not multi:
            return Rendezvous(point, step)
        return Rendezvous(point, step, theirs, self.backup(view, point, theirs, step))

    def relay_point(self, view: RobotView, point: tuple[float, float]) -> tuple[float, float]:
        """Multi-point: the relay's point for the explorer's ``point`` (recomputed at most
        every :data:`RV_REPLAN_INTERVAL` steps or when the explorer's point moved)."""
        last = self.multi
        fresh = last is not None and view.step - last[0] < RV_REPLAN_INTERVAL
        if last is None or not fresh or math.dist(last[1].explorer, point) > MIN_RV_DISTANCE:
            context = plan_context(view)
            reach = view.comm_range
            choice = relay_point(
                view.belief, context.passable, context.passable_box, point,
                view.base_position, reach,
            )  # fmt: skip
            self.multi = last = (view.step, choice)
        return last[1].relay

    def backup(
        self, view: RobotView, point: tuple[float, float], theirs: tuple[float, float], step: int
    ) -> Rendezvous:
        """The backup meeting: where the pair stands now (they are linked here), once the
        wait is over and both could have walked there from their points."""
        here = (float(view.position[0]), float(view.position[1]))
        trip = max(math.dist(point, here), math.dist(theirs, here)) / view.speed
        return Rendezvous(here, step + self.wait + math.ceil(trip))

    def views(self) -> dict[str, FloatArray]:
        """The multi-point layers: the potential points and those linked through walls."""
        if self.multi is None:
            return {}
        return {
            "rv_candidates": self.multi[1].candidates,
            "rv_through_walls": self.multi[1].through_walls,
        }

    def forget(self) -> None:
        """Drop the last multi-point choice (the pair's roles changed)."""
        self.multi = None


def overdue(meeting: Rendezvous | None, step: int) -> bool:
    """Whether ``meeting``'s agreed time has passed. Partners that meet after it have kept
    or missed it; neither may set out for it again. Before, the pair kept it when their
    contact lasted one step, so no new agreement was bound, and shuttled between the old
    point and the base (scenario 23, seeds 10, 13 and 18: stalled at 78.9 % explored)."""
    return meeting is not None and step > meeting.step


def improved_point(view: RobotView, frontier: tuple[float, float]) -> tuple[float, float] | None:
    """The original's improved rendezvous: of the skeleton junctions of the robot's known
    space within :data:`IMPROVED_REACH` cells of the frontier, the
    :data:`IMPROVED_CANDIDATES` nearest, scored by ``degree**2 * 1e4 / distance`` to the
    frontier (straight lines; the original: path length); None without a junction."""
    topology = plan_context(view).topology()
    junctions = topology.junctions
    if len(junctions) == 0:
        return None
    centres = junctions[:, ::-1] + 0.5  # (x, y)
    distance = np.hypot(*(centres - np.asarray(frontier)).T)
    near = np.flatnonzero(distance <= IMPROVED_REACH)
    if len(near) == 0:
        return None
    near = near[np.argsort(distance[near], kind="stable")[:IMPROVED_CANDIDATES]]
    skeleton = topology.skeleton
    degree = np.array([
        int(skeleton[max(r - 1, 0) : r + 2, max(c - 1, 0) : c + 2].sum()) - 1
        for r, c in junctions[near]
    ])  # fmt: skip
    score = degree.astype(float) ** 2 * 1e4 / np.maximum(distance[near], 1.0)
    best = near[int(np.argmax(score))]
    return float(centres[best, 0]), float(centres[best, 1])
