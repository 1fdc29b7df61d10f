"""The simulation cycle (paper, Algorithm 1): one :meth:`Simulation.step` per time step.

Each step runs the phases in order::

    events -> decide -> move and sense -> place -> communicate -> measure

Events (``world/events.py`` plugins) act first; then every robot that can move
decides: it takes a decision a caller supplied (``step(actions=...)``: a viewer,
a learning agent) or asks its strategy when a replan is due. Then each robot
moves up to its speed along its path, scanning after each path point and
replanning mid-step when its path runs out (``motion``); then robot bodies are
placed in the world; then links are found and knowledge exchanged (``comms``);
then the step is measured (``metrics``). Robots act as if simultaneously: during
the decide and movement phases a robot reads and writes only its own state (teammate
records change only in the communication phase, other robots' bodies stay where the
step began), so the order in which robots are processed never changes the result.
That is why a robot's due replan and its move run as one task per robot, on
``simulation.threads`` threads (``parallel.py``), whose effects on shared state
(team coverage, comm ledger, timers) are applied in robot order afterwards.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from functools import partial
from pathlib import Path
from time import perf_counter
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mresim_phys.agent_views import agent_snapshot, robot_view, static_fields
from mresim_phys.agents import Agent, Robot
from mresim_phys.build import Scenario, Setup, build_setup, load_scenario
from mresim_phys.clocks.gate import acts, decide_phase, may_decide, settle, tick
from mresim_phys.comms.ledger import box_around, sensed_tick
from mresim_phys.comms.radio_feature import radio_columns
from mresim_phys.discovery_feature import count_discoveries, watch_discoveries
from mresim_phys.errors import ScenarioError, UnknownRobotError
from mresim_phys.event_context import RunEventContext
from mresim_phys.faults.runtime import hazard_grid
from mresim_phys.features import FEATURES
from mresim_phys.health_phase import robot_steps
from mresim_phys.knowledge.health import HealthWatch
from mresim_phys.knowledge.latest import LatestCoverage
from mresim_phys.knowledge.robustness import FailureWatch, robot_states
from mresim_phys.knowledge.teammates import presumed_lost
from mresim_phys.localization.corrections import landmark_fixes, teammate_fixes
from mresim_phys.localization.faults import frozen
from mresim_phys.localization.feature import LOCALIZATION
from mresim_phys.meetings.watch import meeting_watch
from mresim_phys.memory import keep_freed_memory
from mresim_phys.metrics import (
    RobotRecord,
    StepRecord,
    base_latency,
    measure_step,
    update_known_at_base,
)
from mresim_phys.motion import MoveRules, replans_on_the_way, take_step
from mresim_phys.parallel import Effects, RobotPool, thread_count
from mresim_phys.sensing_phase import Senses
from mresim_phys.snapshot import CommSummary, Snapshot, read_only
from mresim_phys.stop_rules import stop_reason
from mresim_phys.strategies import Decision, RobotView, relax
from mresim_phys.tracking import (
    CommTotals,
    Curves,
    Milestones,
    StallWatch,
    budget_level,
    thresholds_with,
)
from mresim_phys.world.views import movable_views

PHASES = ("sensing", "mapping", "planning", "communication", "metrics")


class Simulation:
    """A running scenario: the world, the agents and the per-step records.

    Built from a validated, picklable :class:`~mresim_phys.scenario.schema.Scenario`
    alone (so another process can rebuild it). ``phase_times`` accumulates the wall
    time spent in each phase (seconds): what ``mresim bench`` reports as the cost
    split; it never enters the metrics.
    """

    def __init__(self, scenario: Scenario) -> None:
        keep_freed_memory()  # big arrays come back from the heap, not from page faults
        self.scenario = scenario
        self.setup: Setup = build_setup(scenario)
        s = self.setup
        self.world, self.base, self.robots = s.world, s.base, s.robots
        self.coverage, self.network, self.rules = s.coverage, s.network, s.rules
        self.t = 0
        self.ignored_actions: tuple[str, ...] = ()  # decisions for robots that cannot move
        self.phase_times: dict[str, float] = dict.fromkeys(PHASES, 0.0)
        self.events_now: list[str] = []
        self.comm = self.network.idle(len(self.agents))
        self.known_at_base = 0.0
        self.known_at_base_connected: float | None = 0.0  # over the connected free cells
        levels = [*scenario.metrics.levels, *budget_level(scenario.metrics.budget)]
        self.milestones = Milestones(thresholds_with(levels))
        self.comm_totals = CommTotals(radio=radio_columns(self.scenario.communication))
        self.stall = StallWatch(s.rules.stalled_for, s.rules.stalled_gain)
        self.curves = Curves()
        self.failures = FailureWatch([r.name for r in self.robots])
        self.health = HealthWatch([r.name for r in self.robots])  # idle, stuck, state reasons
        self.fault_columns = s.rules.fault_columns  # metrics.csv has the robustness columns
        self.senses = Senses(s.world, s.rules.robots_block, s.terrain, s.sensing_streams())
        # the hazard zones' failure probability per cell and step (static; None: no zones)
        self.hazards: NDArray[np.float32] | None = hazard_grid(s.faults, s.world.shape)
        self._statics = static_fields(s, scenario.dt, self.hazards)  # what every snapshot holds
        self._events = RunEventContext(
            self.agents, s.network, s.world, s.coverage, (s.reachable, s.explorable),
            s.event_streams(), s.elements,
        )  # fmt: skip
        ground = None if s.ground is None else s.ground.grid
        self.move_rules = MoveRules(s.rules.scan_every_point, self.robot_filter, s.terrain, ground)
        self.pool = RobotPool(thread_count(scenario.simulation.threads, len(self.robots)))
        self.apply_events()
        self._stamped: frozenset[int] = frozenset()  # robots whose task stamped the ledger
        for robot in self.robots:
            self.sense_in_place(robot)
        self.communicate()
        self.drain_batteries()
        self.meetings = meeting_watch([a.name for a in self.agents], self.robots)  # or None
        self.record = self.measure()

    @classmethod
    def from_yaml(cls, path: str | Path, **overrides: Any) -> Simulation:
        """Load, validate and build the scenario at ``path`` (overrides merge deeply:
        ``seed=``, ``steps=``, ``team=``, ``robots={"B": {...}}``, ``**{"team.speed": 5}``)."""
        scenario = load_scenario(path, **overrides)
        try:
            return cls(scenario)
        except ScenarioError as exc:
            raise ScenarioError(f"{path}: {exc}") from None

    @property
    def agents(self) -> list[Agent]:
        """Base station (index 0) then robots, the order of the link matrix."""
        return [self.base, *self.robots]

    def robot(self, name: str) -> Robot:
        """The robot called ``name``; UnknownRobotError (a KeyError) naming the team if none."""
        for robot in self.robots:
            if robot.name == name:
                return robot
        team = ", ".join(repr(r.name) for r in self.robots)
        raise UnknownRobotError(f"no robot {name!r} in this run; its robots are {team}")

    def step(self, actions: Mapping[str, Decision] | None = None) -> StepRecord:
        """Advance one time step and return its measurements.

        ``actions`` maps robot names to decisions that replace their strategies' for
        this step (the robot follows the given path; its strategy is not asked).
        """
        self.open_step()
        return self.close_step(actions)

    def open_step(self) -> None:
        """Start the next step up to its decide phase: its events, then the robots' clocks
        (a learning environment looks at who decides now between this and
        :meth:`close_step`; ``mresim_phys/learn``)."""
        self.t += 1
        self.apply_events()
        tick(self.robots, self.t)

    def close_step(self, actions: Mapping[str, Decision] | None = None) -> StepRecord:
        """The rest of the step :meth:`open_step` started, from its decide phase on."""
        given, due = self.decide(actions or {})
        self.move_and_sense(given, due)
        self.world.place_robots([r.position for r in self.robots])
        self.communicate()
        teammate_fixes(self.robots)
        self.drain_batteries()
        self.record = self.measure()
        return self.record

    def run(self, on_step: Callable[[StepRecord], None] | None = None) -> StepRecord:
        """Step until the step cap or a stop rule; ``on_step`` sees every record."""
        for record in self.iterate():
            if on_step is not None:
                on_step(record)
        return self.record

    def iterate(self) -> Iterator[StepRecord]:
        """Yield the step-0 record, then one record per step until the run stops."""
        yield self.record
        while not self.finished():
            yield self.step()

    def finished(self) -> bool:
        """The step cap is reached or a stop rule holds."""
        return self.stop_reason() is not None

    def stop_reason(self) -> str | None:
        """Why the run stops now (``steps``, ``explored``, ``known_at_base``, ``all_done``,
        ``stalled``: ``stop_rules.py``)."""
        return stop_reason(self.rules, self.record, self.robots, self.stall)

    def apply_events(self) -> None:
        """Events phase: every scheduled event acts through the run's event context, then
        the random faults (``faults/``), if the scenario has any."""
        self.events_now = self._events.run(self.setup.events, self.t)
        if self.setup.faults is not None:
            self.events_now += self.setup.faults.apply(self.t)

    def drain_batteries(self) -> None:
        """After the communication phase: batteries pay for the step (``faults/``)."""
        if self.setup.faults is not None:
            sent = [self.comm.traffic.sent, self.comm.control_traffic.sent]
            self.events_now += self.setup.faults.drain(sent, self.t)

    def decide(self, actions: Mapping[str, Decision]) -> tuple[set[str], set[str]]:
        """Decide phase: supplied decisions are adopted; returns (given, due).

        ``given``: the robots that follow a caller's decision this step (their strategies
        are not asked; a decision for a robot that failed, or whose drive did, is ignored
        and named in ``ignored_actions``); ``due``: the robots whose replan is due, asked by
        :meth:`move_and_sense` before they move (a replan reads only the robot's own
        knowledge, so asking then is the same as asking now). A robot with a clock
        (``clocks/gate.py``) decides only on its steps and within its decision period; a
        caller's decision for it waits for its next step.
        """
        unknown = sorted(set(actions) - {r.name for r in self.robots}) if actions else []
        if unknown:
            raise ValueError(f"actions name robots the team does not have: {unknown}")
        self.ignored_actions = tuple(
            r.name for r in self.robots if r.name in actions and not r.can_move
        )
        return decide_phase(self.robots, actions, self.t)

    def move_and_sense(self, given: set[str], due: set[str]) -> None:
        """Move phase: each robot replans if due, then moves up to its speed, scanning (and
        replanning) on the way; one task per robot (on threads if ``simulation.threads``
        allows), shared effects applied in robot order afterwards. A robot whose drive has
        failed (and whose sensor works) scans once where it stands."""
        movers = [r for r in self.robots if r.can_move and acts(r)]
        tasks = [partial(self.robot_turn, r, r.name in due, r.name in given) for r in movers]
        threaded = self.pool.threads > 1
        heavy = [r.name in due or replans_on_the_way(r) for r in movers] if threaded else []
        for effects in self.pool.run(tasks, heavy):
            self.apply(effects)
        count_discoveries(movers)
        self._stamped = frozenset(r.index for r in movers)
        for robot in self.robots:
            if robot.alive and not robot.can_move and robot.can_sense:
                self.sense_in_place(robot)

    def sense_in_place(self, robot: Robot) -> None:
        """A scan where ``robot`` stands, outside the robots' tasks (at the start of a run,
        or for a robot whose drive has failed); the ledger learns its window at once."""
        effects = Effects.of(robot)
        found = watch_discoveries(robot)
        self.sense(robot, effects)
        if found is not None:
            found.seen(robot.belief)
            found.count()
        self.apply(effects)
        if effects.window is not None:
            self.network.note_scan(robot.index, effects.window)

    def robot_turn(self, robot: Robot, due: bool, given: bool) -> Effects:
        """One robot's decide and move phases, then the stamping of its own changes in the
        comm ledger (which the communication phase would do otherwise: nothing changes the
        robot's map in between); what they did to shared state, held back."""
        effects = Effects.of(robot)
        found = watch_discoveries(robot)
        if due:
            self.replan(robot, effects)
        replan, sense = partial(self.replan, effects=effects), partial(self.sense, effects=effects)
        queue = self.senses.queue_for(robot)  # scans held back and folded together
        if queue is None:
            take_step(robot, self.world, self.move_rules, given, replan, sense)
        else:
            hold = partial(self.senses.hold, queue=queue)
            settle = partial(self.senses.fold_held, queue, effects)
            take_step(robot, self.world, self.move_rules, given, replan, hold, settle)
        if found is not None:
            found.seen(robot.belief)
        loc = LOCALIZATION.state_of(robot.features)
        if loc is not None and not frozen(robot.features):  # the base and beacons seen from here
            landmark_fixes(loc, self.base.position, self.world, self.robot_filter(robot))
        started = perf_counter()
        self.network.stamp_own(robot, effects.window, self.t)
        effects.spend("communication", perf_counter() - started)
        return effects

    def apply(self, effects: Effects) -> None:
        """Fold one robot's held-back effects into the team coverage and timers."""
        effects.apply(self.coverage.touch_box, self.phase_times)

    def robot_filter(self, robot: Robot) -> tuple[int, int, int]:
        """What ``robot``'s rays and motion collide with."""
        return self.senses.filter_of(robot)

    def sense(self, robot: Robot, effects: Effects) -> None:
        """Scan at the robot's pose into its map (``sensing_phase.Senses.sense``)."""
        self.senses.sense(robot, effects, self.t)

    def replan(self, robot: Robot, effects: Effects) -> None:
        """Ask the robot's strategy for a new path from what the robot knows (unless its
        clock forbids it now); followed now or when its compute delay has passed."""
        assert robot.strategy is not None
        if not may_decide(robot, self.t):
            return
        started = perf_counter()
        settle(robot, relax.decide(robot.strategy, self.view_of(robot)), self.t)
        effects.spend("planning", perf_counter() - started)

    def view_of(self, robot: Robot) -> RobotView:
        """The robot's knowledge, read-only, as its strategy may see it."""
        setup = self.setup
        return robot_view(
            robot, self.t, self.base.position, self.rules.presume_lost_after,
            setup.team_order, self.rules.vary_with_seed, setup.free_area,
        )  # fmt: skip

    @property
    def links(self) -> np.ndarray:
        """This step's main-channel links (index 0 = base)."""
        return self.comm.links

    def communicate(self) -> None:
        """Find links among alive agents and exchange knowledge along them."""
        started = perf_counter()
        for robot in self.robots:
            if robot.index not in self._stamped:
                self.network.note_body(robot)
        self.comm = self.network.communicate(
            self.agents, self.world, self.t, self.pool.run_in_chunks, self._stamped
        )
        self._stamped = frozenset()
        self.note_links()
        if isinstance(self.coverage, LatestCoverage):
            self.touch_merged(self.coverage)
        if self.links[0].any() or self.t == 0 or self.network.base_received:
            self.known_at_base, self.known_at_base_connected = update_known_at_base(
                (self.known_at_base, self.known_at_base_connected),
                self.base.belief, self.coverage, not self.rules.latest,
            )  # fmt: skip
        self.phase_times["communication"] += perf_counter() - started

    def touch_merged(self, coverage: LatestCoverage) -> None:
        """'latest' beliefs: a merge (or a bump) may take a FREE cell out of a robot's
        map, so the explored count looks at the boxes merges changed this step too."""
        ledger = self.network.ledger
        for robot in self.robots:
            for box in ledger.newer_boxes(robot.index, sensed_tick(self.t)).tolist():
                coverage.touch_box(robot.belief, (box[0], box[1], box[2], box[3]))
            around = box_around(robot.believed_position, robot.radius + 2, self.world.shape)
            coverage.touch_box(robot.belief, around)

    def note_links(self) -> None:
        """Tell every agent whom it is linked with on the main channel now."""
        agents = self.agents
        for agent, row in zip(agents, self.links, strict=True):
            agent.links = tuple(agents[j].name for j in np.flatnonzero(row))

    def snapshot(self) -> Snapshot:
        """The run at the end of the current step (views of the live grids, not copies)."""
        silence = self.rules.presume_lost_after
        agents = [
            agent_snapshot(a, presumed_lost(a.teammates, self.t, silence), self.health.view(a.name))
            for a in self.agents
        ]
        rubble, gave_way = self.world.debris() or (None, None)
        record, comm = self.record, self.comm
        control = comm.control_links.copy() if self.network.control else None
        return Snapshot(
            **self._statics,
            step=self.t,
            explored=record.explored,
            known_at_base=record.known_at_base,
            alive=record.alive,
            truth=read_only(self.world.occupied),
            agents=tuple(agents),
            links=self.links.copy(),
            events=tuple(self.events_now),
            comm=CommSummary.of(record, control, comm.traffic.sent.copy()),
            world_version=self.world.version,
            movables=movable_views(self.world, self.setup.elements),
            rubble=rubble,
            gave_way=gave_way,
            lost_knowledge=self.failures.lost_view(),
            failures=self.failures.notes(),
            meetings=record.meetings,
        )

    def measure(self) -> StepRecord:
        """This step's row of metrics."""
        started = perf_counter()
        self.coverage.settle()
        robots = tuple(
            RobotRecord(
                r.name,
                r.distance,
                r.state,
                r.last_base_contact,
                FEATURES.recorded_values(r.features),
            )
            for r in self.robots
        )
        heard = {name: info.step for name, info in self.base.teammates.items()}
        watch, coverage = self.failures, self.coverage
        watch.update(self.t, robot_states(self.robots), self.base.belief, coverage.reachable,
                     coverage.total)  # fmt: skip
        self.health.update(self.t, robot_steps(self.robots, self.health, self.t, self.events_now))
        latency = base_latency(self.t, heard, [r.name for r in self.robots if r.alive])
        judge = self.meetings  # the rendezvous accounting (meetings/), if the run has one
        meetings = None if judge is None else judge.update(self.t, self.links, self.robots)
        record = measure_step(
            self.t,
            self.coverage,
            self.known_at_base,
            robots,
            self.links,
            control_links=self.comm.control_links,
            comm_bytes=self.comm.traffic.total,
            control_bytes=self.comm.control_traffic.total,
            latency=latency,
            robustness=watch.columns() if self.fault_columns else None,
            known_at_base_connected=self.known_at_base_connected,
            meetings=meetings,
        )
        self.milestones.update(record)
        self.curves.update(record)
        self.comm_totals.update(record)
        self.stall.update(record)
        self.health.note_progress(self.t, record.explored, record.known_at_base)
        self.phase_times["metrics"] += perf_counter() - started
        return record
