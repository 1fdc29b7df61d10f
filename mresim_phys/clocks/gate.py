"""Robot clocks at work (phase 1, decide): the gates ``sim.py`` asks before a robot acts,
decides and scans, and where a plan asked for waits until it takes effect.

Each step, after the events, :func:`tick` moves every clock to the step (a robot that
failed loses the plan it was waiting for; one back from a failure starts its clock again
on the step it came back). Then, for a robot with a clock (docs/clocks.md):

* it acts only on its steps (:func:`acts`): on the others it neither moves, decides nor
  scans; it still communicates;
* a caller's decision (``Simulation.step(actions=...)``) is followed on its next step it
  acts on (:func:`follows_given`), replacing any plan its strategy had asked for;
* its strategy is asked when a replan is due and ``decision_period`` steps have passed
  since it was last asked, never while a plan is pending, and not on the step a plan that
  waited takes effect (:func:`may_decide`): what the plan carries (a rendezvous proposal)
  goes out with the robot's record at that step's exchange before its strategy decides
  again, as it does without a delay;
* the plan it asks for takes effect ``compute_delay`` steps later (:func:`settle`): until
  then it follows its old path (or stands). A plan that takes effect after the robot moved
  on is joined where the robot is (:func:`joined`: from the path point nearest to it);
* it scans on a step at least ``scan_period`` steps after the step of its last scan
  (``Clock.scan``, asked by ``sensing_phase.Senses.takes_scan``).

A robot without a clock passes every gate and adopts every decision at once, as before.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import replace

import numpy as np

from mresim_phys.agents import Robot
from mresim_phys.clocks.feature import CLOCK, Clock
from mresim_phys.motion import wants_plan
from mresim_phys.strategies import Decision


def decide_phase(
    robots: Sequence[Robot], actions: Mapping[str, Decision], step: int
) -> tuple[set[str], set[str]]:
    """The decide phase (``Simulation.decide``): (given, due). ``given``: the robots that
    follow a caller's decision at ``step``; ``due``: those that act on it, may decide
    and whose replan is due (``motion.wants_plan``)."""
    given: set[str] = set()
    due: set[str] = set()
    for robot in robots:
        if not robot.can_move:
            continue
        assert robot.strategy is not None
        if follows_given(robot, actions.get(robot.name), step):
            given.add(robot.name)
        elif (
            acts(robot)
            and may_decide(robot, step)
            and wants_plan(robot, step, robot.strategy.params.replan_interval)
        ):
            due.add(robot.name)
    return given, due


def tick(robots: Sequence[Robot], step: int) -> None:
    """Move every robot's clock to ``step`` (after the events phase)."""
    for robot in robots:
        clock = CLOCK.state_of(robot.features)
        if clock is not None:
            advance(clock, robot.alive, step)


def advance(clock: Clock, alive: bool, step: int) -> None:
    """``clock`` at ``step`` for a robot ``alive`` or not."""
    clock.now = step
    if not alive:  # a failure drops the plan it waited for, and a caller's held decision
        clock.pending = clock.held = None
    elif not clock.was_alive:  # back from a failure: its clock starts again now
        clock.origin, clock.last_decided, clock.last_scan = step, None, None
    clock.was_alive = alive
    spec = clock.spec
    clock.acting = alive and (step - clock.origin) % spec.act_every == 0
    since = math.inf if clock.last_scan is None else step - clock.last_scan
    clock.scanning = clock.acting and since >= spec.scan_period


def acts(robot: Robot) -> bool:
    """Whether the robot acts (moves, decides, scans) on this step."""
    clock = CLOCK.state_of(robot.features)
    return clock is None or clock.acting


def may_decide(robot: Robot, step: int) -> bool:
    """Whether the robot's strategy may be asked at ``step``: no plan pending, its decision
    period passed since it was last asked, and no plan that waited took effect on this step
    (a strategy's next decision comes after the exchange that carried its last one)."""
    clock = CLOCK.state_of(robot.features)
    return clock is None or (clock.pending is None and clock.ready_in(step) == 0)


def settle(robot: Robot, decision: Decision, step: int) -> None:
    """The decision its strategy made at ``step``: followed now, or pending until its
    compute delay has passed."""
    clock = CLOCK.state_of(robot.features)
    if clock is None:
        robot.adopt(decision, step)
        return
    clock.decisions += 1
    clock.last_decided = step
    delay = clock.delay()
    if delay == 0:
        robot.adopt(decision, step)
    else:
        clock.pending, clock.decided_at, clock.due_at = decision, step, step + delay
        clock.odometer = robot.distance


def follows_given(robot: Robot, action: Decision | None, step: int) -> bool:
    """Decide phase for a robot that can move: whether it follows a caller's decision this
    step (given now, or held from a step it did not act on); else a plan of its strategy
    whose delay has passed takes effect."""
    clock = CLOCK.state_of(robot.features)
    if clock is None:
        if action is not None:
            robot.adopt(action, step)
        return action is not None
    if action is not None:
        clock.held = action  # the newest a caller gave
    if not clock.acting:
        return False
    if clock.held is not None:
        robot.adopt(clock.held, step)
        clock.held = clock.pending = None
        return True
    if clock.pending is not None and step >= clock.due_at:
        moved = robot.distance > clock.odometer
        plan = clock.pending
        robot.adopt(joined(plan, robot.believed_position) if moved else plan, step)
        clock.pending, clock.applied_at = None, step
    return False


def joined(decision: Decision, position: tuple[float, float]) -> Decision:
    """``decision`` followed from the point of its path nearest to ``position`` (the robot
    moved on its old path while the plan was computed)."""
    path = decision.path
    if len(path) < 2:
        return decision
    gaps = np.hypot(path[:, 0] - position[0], path[:, 1] - position[1])
    nearest = int(np.argmin(gaps))
    return replace(decision, path=path[nearest:]) if nearest else decision
