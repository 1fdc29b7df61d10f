"""``policy`` (phase 4, decide): a robot whose decisions come from a trained policy or from a
learning environment.

When its decision is due (its ``replan_interval``, on reaching its target, after an error;
every step it acts with ``velocity`` actions; never against its clock, ``clocks/``) the
robot builds its observation from its view (``observe.py``), asks its policy for an action
(``loaders.py``), or takes the one a learning environment left in :attr:`answer`, and
heads where the action says (``actions.py``). It decides once a step, at the step's decide
phase (``ONE_DECISION_PER_STEP``: a robot that reaches its target with movement left waits
there for the next step), where an environment can ask for its action: a run with an
environment answering and the same run with the policy inside are the same run. It is never
``done``: a run of ``policy`` robots ends at its step cap or an ``explored`` stop rule.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from mresim_phys.plugin import Plugin
from mresim_phys.strategies.base import Decision, PlanContext, RobotView, plan_context
from mresim_phys.strategies.catalog import STRATEGIES
from mresim_phys.strategies.giveup import Tried, tried_after_arrival
from mresim_phys.strategies.params import PolicyParams, StrategyParams
from mresim_phys.strategies.policy.actions import (
    Target,
    choice_target,
    chosen_slot,
    goal_target,
    toward,
    velocity_decision,
)
from mresim_phys.strategies.policy.candidates import (
    CONTINUE,
    Candidates,
    find_candidates,
    slot_count,
)
from mresim_phys.strategies.policy.loaders import load_policy
from mresim_phys.strategies.policy.observe import Observation, observe
from mresim_phys.types import IntArray


@STRATEGIES.register
class PolicyStrategy(Plugin):
    """A trained policy's decisions (a callable, an ONNX file) or a learning environment's;
    exactly one of policy, onnx and external (docs/learning.md)."""

    name = "policy"
    ONE_DECISION_PER_STEP = True  # never asked again within a step (motion.take_step)

    Params: ClassVar[type[StrategyParams]] = PolicyParams
    params: PolicyParams

    def __init__(self, params: PolicyParams) -> None:
        self.params = params
        self.slots = slot_count(params.frontiers, params.meet)
        slots = self.slots if params.action == "choice" else None
        self.chooser = load_policy(params.policy, params.onnx, slots)
        self.answer: Any = None  # a learning environment's action for the next decision
        self.target: Target | None = None  # where it heads now, and the point it then faces
        self.last_action: Any = None
        # the step, position, planning helpers and table of its last look (one a step)
        self._looked: tuple[int, tuple[float, float], PlanContext, Candidates] | None = None
        self._tried: Tried | None = None
        self._decided_at = -1  # the step of its last decision
        self._chasing: IntArray | None = None  # the cells of the frontier it heads for

    def observation(self, view: RobotView, asked: bool) -> Observation:
        """What its policy sees now; ``asked``: whether its decision is asked now (the
        candidate table is found only then: a robot not asked may only continue)."""
        candidates = self.look(view)[1] if asked else self.idle_table()
        return observe(view, candidates, self.params, sorted(view.team_order), asked)

    def look(self, view: RobotView) -> tuple[PlanContext, Candidates]:
        """The planning helpers and candidate table at ``view``, found once per step and
        position (an environment's look before the step's decide phase serves it too:
        the robot's map does not change in between)."""
        looked = self._looked
        if looked is not None and looked[0] == view.step and looked[1] == view.position:
            return looked[2], looked[3]
        context, found = plan_context(view), Candidates.empty(self.slots)
        if self.params.action == "choice":
            current = None if self.target is None else self.target[0]
            p, tried = self.params, self.tried(view)
            found = find_candidates(view, context, p.frontiers, p.meet, current, tried)
        self._looked = (view.step, view.position, context, found)
        return context, found

    def tried(self, view: RobotView) -> Tried:
        """The frontiers it reached in vain (``giveup``); one it has just reached and still
        holds counts a try."""
        self._tried, self._chasing = tried_after_arrival(
            self._tried, view.belief.shape, view.reached_goal, self._chasing, view.position,
            self.params.give_up_radius,
        )  # fmt: skip
        return self._tried

    def idle_table(self) -> Candidates:
        """The table of a robot not asked: only ``continue``, at its target."""
        table = Candidates.empty(self.slots)
        if self.target is not None:
            table.points[CONTINUE] = self.target[0]
        return table

    def decide(self, view: RobotView) -> Decision:
        """Ask the policy (or take the environment's answer) and head where it says."""
        context, candidates = self.look(view)
        action = self.action(view, candidates)
        self.last_action = action
        if self.params.action == "velocity":
            return velocity_decision(context, action)
        if self.params.action == "choice":
            self.target = choice_target(action, candidates, self.target)
            self._chasing = chased(action, candidates, self._chasing)
        else:
            self.target = goal_target(action, view.belief.shape)
        return toward(context, self.target, action)

    def action(self, view: RobotView, candidates: Candidates) -> Any:
        """One decision a step: the environment's answer if it left one, else the policy's;
        asked again within the step (or with neither): continue."""
        if self._decided_at == view.step:
            return CONTINUE if self.params.action == "choice" else self.held()
        self._decided_at = view.step
        if self.answer is not None:
            action, self.answer = self.answer, None
            return action
        if self.chooser is None:
            return CONTINUE if self.params.action == "choice" else self.held()
        obs = observe(view, candidates, self.params, sorted(view.team_order), True)
        return self.chooser(obs)

    def held(self) -> Any:
        """The last action again (goal and velocity actions), or standing still."""
        if self.last_action is not None and self.params.action == "goal_cell":
            return self.last_action
        return np.zeros(2)

    def replan_now(self, step: int, position: tuple[float, float], links: tuple[str, ...]) -> bool:
        """With ``velocity`` actions, every step it acts."""
        return self.params.action == "velocity"


def chased(action: Any, candidates: Candidates, chasing: IntArray | None) -> IntArray | None:
    """The frontier cells a choice ``action`` heads for: its slot's cluster (a frontier
    slot), none (another valid slot), or still ``chasing`` (continue, or an invalid slot)."""
    slot = chosen_slot(action, candidates)
    if slot is None:
        return chasing
    return candidates.clusters[slot] if slot < len(candidates.clusters) else None
