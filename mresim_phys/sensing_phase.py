"""Phase 5 (sense, then map): a robot's scans during its turn, folded into its own map.

:class:`Senses` scans where a robot stands and folds the scan into its map: in one compiled
call when nothing needs to happen between the cast and the fold (``knowledge.scanfold``),
else cast (with range noise from the robot's seeded stream), folded and stamped for
'latest' beliefs in turn (with localisation: cast from the true pose, matched to the
robot's map if it does scan matching, folded at its believed pose:
``localization/perceive.py``); it learns the terrain the scan saw and drops a path the new
map shows blocked (with 'latest' beliefs or a prior map). Within a robot's turn the scans it
takes after each path point can be held back (:meth:`Senses.queue_for`) and folded
together when the turn next reads or writes the map (``motion.take_step``'s ``settle``).
What a scan touched (its window, its time) goes into the turn's
:class:`~mresim_phys.parallel.Effects`, never straight into shared state.
"""

from __future__ import annotations

from time import perf_counter

import numpy as np

from mresim_phys.agents import Robot
from mresim_phys.clocks.feature import CLOCK
from mresim_phys.knowledge.beamfold import BeamScanQueue
from mresim_phys.knowledge.evidence import integrate_evidence
from mresim_phys.knowledge.latest import LATEST
from mresim_phys.knowledge.mapping import Update, integrate_scan
from mresim_phys.knowledge.prior import PRIOR
from mresim_phys.knowledge.scanfold import (
    ScanQueue,
    fold_placed,
    folds_in_one_call,
    scan_into_map,
)
from mresim_phys.knowledge.terrain import TERRAIN, learn_terrain
from mresim_phys.localization.faults import frozen
from mresim_phys.localization.feature import LOCALIZATION
from mresim_phys.localization.perceive import as_believed, match_scan
from mresim_phys.motion import path_blocked
from mresim_phys.parallel import Effects
from mresim_phys.readings_feature import beam_state
from mresim_phys.world.beam import read_beam
from mresim_phys.world.queries import QueryFilter
from mresim_phys.world.sensing import scan
from mresim_phys.world.space import Scan, World
from mresim_phys.world.terrain import TerrainGrid

LOOKAHEAD_STEPS = 3  # 'latest' beliefs: a path blocked within this many steps is dropped


class Senses:
    """Scans of the robots of one run: what their rays hit, how scans fold into maps."""

    def __init__(
        self,
        world: World,
        robots_block: bool,
        terrain: TerrainGrid | None,
        streams: list[np.random.Generator],
    ) -> None:
        self.world, self.robots_block, self.terrain = world, robots_block, terrain
        self.streams = streams  # per robot (index - 1): range noise

    def filter_of(self, robot: Robot) -> QueryFilter:
        """What ``robot``'s rays and motion collide with."""
        return self.world.query_filter(robot.index - 1, self.robots_block)

    def sense(self, robot: Robot, effects: Effects, step: int) -> None:
        """Scan at the robot's pose and fold the scan into its map; note the touched window
        for the team coverage and the ledger in ``effects``."""
        if not self.takes_scan(robot):
            return
        laser, observed = robot.laser, LATEST.state_of(robot.features)
        loc = LOCALIZATION.state_of(robot.features)
        started = perf_counter()
        matches = loc is not None and loc.matching is not None
        if not matches and folds_in_one_call(laser, observed):  # the fold is timed as sensing
            update = scan_into_map(
                self.world, robot.position, robot.heading, laser, self.filter_of(robot),
                robot.belief, robot.safe, None if loc is None else loc.believed,
            )  # fmt: skip
            scanned = perf_counter()
        else:
            result = self.read(robot)
            if loc is not None and not frozen(robot.features):
                match_scan(loc, robot.belief, result)  # then folded where it believes it is
            scanned = perf_counter()
            update = self.fold(robot, result, observed, step)
        known = TERRAIN.state_of(robot.features)
        if update is not None and known is not None and self.terrain is not None:
            learn_terrain(known, self.terrain, update)
        effects.spend("sensing", scanned - started)
        effects.spend("mapping", perf_counter() - scanned)
        lookahead = LOOKAHEAD_STEPS * robot.speed
        checks_path = observed is not None or PRIOR.key in robot.features
        if checks_path and path_blocked(robot.belief, robot.path, robot.radius, lookahead):
            robot.stop_for_replan()
        if update is not None:
            effects.scanned(robot.belief, update)

    def read(self, robot: Robot) -> Scan:
        """The robot's scan where it stands: the exact cast with its range noise, or read
        through its beam model."""
        stream = self.streams[robot.index - 1]
        where, laser, shapes = robot.position, robot.laser, self.filter_of(robot)
        result = scan(self.world, where, robot.heading, laser, shapes, stream)
        state = beam_state(robot.features)
        if laser.beam is None or state is None:
            return result
        return read_beam(result, laser.beam, stream, state.counts)

    def fold(
        self, robot: Robot, result: Scan, observed: np.ndarray | None, step: int
    ) -> Update | None:
        """Fold a scan the robot read into its map, where it believes it took it: weighed
        as evidence for a beam-model laser (``knowledge/evidence.py``), else as the truth
        (``knowledge/mapping.py``); the cells it marked FREE."""
        laser, state = robot.laser, beam_state(robot.features)
        loc = LOCALIZATION.state_of(robot.features)
        placed = None if loc is None else loc.believed
        if state is not None and laser.beam is not None:
            maps = (robot.belief, robot.safe, state.evidence)
            radius = laser.safe_fraction * laser.range
            return integrate_evidence(result, robot.heading, maps, radius, placed, observed, step)
        if loc is not None and observed is None:
            return fold_placed(result, robot.heading, laser, robot.belief, robot.safe, loc.believed)
        result = result if loc is None else as_believed(result, loc)
        return integrate_scan(robot.belief, robot.safe, result, laser.safe_fraction, observed, step)

    def queue_for(self, robot: Robot) -> ScanQueue | None:
        """A queue for the robot's scans of this turn (:class:`ScanQueue`; a beam-model
        laser's, :class:`BeamScanQueue`), or None when each scan must fold at once: range
        noise or latest observations (see ``folds_in_one_call``), a path to check against
        every scan, terrain to learn, a scan to match to the map before it folds."""
        observed = LATEST.state_of(robot.features)
        state = beam_state(robot.features) if robot.laser.beam is not None else None
        if state is not None:
            if observed is not None or self.folds_alone(robot):
                return None
            stream = self.streams[robot.index - 1]
            shapes = self.filter_of(robot)
            sinks = (state.counts, state.evidence)
            return BeamScanQueue(self.world, robot.laser, shapes, robot, stream, sinks)
        if not folds_in_one_call(robot.laser, observed) or self.folds_alone(robot):
            return None
        return ScanQueue(self.world, robot.laser, self.filter_of(robot), robot)

    def folds_alone(self, robot: Robot) -> bool:
        """Whether each of the robot's scans must fold at once, whatever its laser: a path
        to check against every scan, a scan to match before it folds, terrain to learn."""
        if PRIOR.key in robot.features:
            return True
        loc = LOCALIZATION.state_of(robot.features)
        if loc is not None and loc.matching is not None:
            return True
        return TERRAIN.key in robot.features and self.terrain is not None

    def hold(self, robot: Robot, queue: ScanQueue) -> None:
        """:meth:`sense`, held in ``queue`` until the robot's map is next read."""
        if self.takes_scan(robot):
            loc = LOCALIZATION.state_of(robot.features)
            queue.add(robot.position, robot.heading, None if loc is None else loc.believed)

    def takes_scan(self, robot: Robot) -> bool:
        """Whether the robot can scan where it stands (a working laser, not buried by a
        change of the world, on a step its clock lets it scan: ``clocks/``); a scan it
        takes is counted."""
        if not robot.can_sense or self.world.buried(robot.position):
            return False
        clock = CLOCK.state_of(robot.features)
        if clock is not None and not clock.scan():
            return False
        robot.scans += 1
        return True

    def fold_held(self, queue: ScanQueue, effects: Effects) -> None:
        """Fold the scans held in ``queue`` (:meth:`ScanQueue.fold`), noted in ``effects``."""
        if queue.poses:
            started = perf_counter()
            window = queue.fold()
            effects.spend("sensing", perf_counter() - started)
            if window is not None:
                effects.scanned_box(queue.robot.belief, window)
