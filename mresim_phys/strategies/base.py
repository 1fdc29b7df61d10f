"""Strategy contract (phase 4, decide): what a robot may know, and what it must decide.

A strategy sees ONLY a :class:`RobotView`: its robot's own belief grid (read
only), its pose and body, the base station position (known before the mission,
as in the original), the last communicated record of each teammate (with the
payload that teammate's strategy sent), whom it is linked with now, when its data
last reached the base and which teammates it presumes lost. It never sees the
true map. It returns a :class:`Decision`: a path of world points to follow, the
goal it is heading for, whether it has nothing left to explore, optionally a new
role, and the payload to send its teammates with its record from now on.

:func:`plan_context` gives a strategy the configuration space and one distance
field from the robot, computed once per decision, plans the path to a chosen
goal with the robot's own planner (``RobotView.planner``) and gives the
topological map of its known space (skeleton, junctions, node regions). A robot
given a prior map plans on it where its own map is unknown (``RobotView.planning_map``).
With
terrain in the scenario, its fields and plans price moves by the terrain the robot
KNOWS (``TERRAIN.of(view)``, never the truth): ``PlanContext.slowness``.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, ClassVar, Protocol, runtime_checkable

import numpy as np

from mresim_phys.ground.feature import GROUND
from mresim_phys.knowledge.known_area import free_box
from mresim_phys.knowledge.prior import PRIOR
from mresim_phys.knowledge.prior import planning_map as belief_with_prior
from mresim_phys.knowledge.teammates import LOST, Payload, TeammateInfo
from mresim_phys.knowledge.terrain import TERRAIN
from mresim_phys.planning import Planner, TopologicalMap, shared_map
from mresim_phys.planning.costs import slowness_of
from mresim_phys.planning.dial import PausedSearch
from mresim_phys.planning.fields import (
    MAX_SNAP,
    DistanceField,
    distance_field,
    passable_cells,
    snap_to_passable,
)
from mresim_phys.planning.goals import nearest_reached
from mresim_phys.planning.grid import Box, bbox, remember_window
from mresim_phys.planning.topological import TopologicalPlanner
from mresim_phys.strategies.params import StrategyParams
from mresim_phys.types import FREE, BeliefGrid, BoolGrid, FloatArray

_RANKS: dict[int, tuple[tuple[str, ...], dict[str, int]]] = {}  # id(order) -> (order, ranks)
MAX_ORDERS = 64  # orders whose ranks are kept (a run has one)


def ranks_of(order: tuple[str, ...]) -> dict[str, int]:
    """Each name's place in ``order`` (its first), found once per order: a simulation gives
    every view the same tuple, and an auction of 128 robots asks for every teammate's."""
    held = _RANKS.get(id(order))
    if held is None or held[0] is not order:
        if len(_RANKS) >= MAX_ORDERS:
            _RANKS.clear()
        ranks = {name: i for i, name in reversed(list(enumerate(order)))}
        held = _RANKS[id(order)] = (order, ranks)
    return held[1]


@dataclass(frozen=True)
class RobotView:
    """Everything a strategy may use to decide: its robot's knowledge, never the truth."""

    step: int
    name: str
    position: tuple[float, float]
    heading: float
    belief: BeliefGrid
    radius: float
    clearance: float
    speed: float
    sensor_range: float
    role: str
    base_position: tuple[float, float]
    teammates: Mapping[str, TeammateInfo]
    rng: np.random.Generator
    bumped: bool = False
    reached_goal: bool = False
    planner: Planner | None = None  # the robot's path planner (None: distance-field paths)
    comm_range: float = 0.0  # its main-channel range (cells)
    links: tuple[str, ...] = ()  # agents it was linked with at the last exchange ('base' too)
    base_contact: int = -1  # last step its data reached the base (-1: never)
    team_order: tuple[str, ...] = ()  # the team's tie-break order (from the seed), the same for all
    vary_with_seed: bool = True  # the scenario lets the seed vary the run (initial random steps)
    free_area: int = 0  # the team's explorable cells, known before the mission (0: not known)
    features: Mapping[str, Any] = field(default_factory=dict)  # each feature's value (features.py)
    parent: str | None = None  # its parent in the team's hierarchy: 'base', a robot, or None
    children: tuple[str, ...] = ()  # the robots whose parent it is
    hops: int = 0  # robots from the base down to it along its parents (0: not under the base)
    escaping: bool = False  # a collision taught its map nothing: it plans wide of corners
    safe: BoolGrid | None = None  # cells it or a teammate it heard scanned from near by

    @property
    def lost(self) -> frozenset[str]:
        """The teammates silent for longer than the run's limit (the feature ``lost``,
        ``knowledge/teammates.py``)."""
        return LOST.of(self) or frozenset()

    @property
    def planning_map(self) -> BeliefGrid:
        """Its belief, and the prior map where its belief is unknown (``knowledge/prior.py``):
        what its paths and distance fields run on. Frontiers stay on its belief."""
        return belief_with_prior(self.belief, PRIOR.of(self))

    def tie_rank(self, name: str) -> int:
        """Where ``name`` stands in the team's tie-break order (unknown names last)."""
        return ranks_of(self.team_order).get(name, len(self.team_order))


@dataclass(frozen=True)
class Decision:
    """A strategy's answer: where to go (path of world points) and why.

    ``goal`` at the robot's own position with no path means "wait here": run health counts
    such a robot as ``waiting``, not idle (``knowledge/health.py``)."""

    path: FloatArray = field(default_factory=lambda: np.zeros((0, 2)))
    goal: tuple[float, float] | None = None
    done: bool = False
    look_at: tuple[float, float] | None = None  # turn to face this point when the path ends
    info: Mapping[str, Any] = field(default_factory=dict)
    role: str | None = None  # the robot's new role (None: keep it)
    payload: Payload | None = None  # sent with the robot's record until its next decision


@runtime_checkable
class Strategy(Protocol):
    """An exploration strategy: one instance per robot, built from its validated params."""

    name: ClassVar[str]
    Params: ClassVar[type[StrategyParams]]

    @property
    def params(self) -> StrategyParams:
        """The validated parameters it was built from (read only: a subclass may narrow it)."""
        ...

    def decide(self, view: RobotView) -> Decision:
        """Choose the robot's next path from what it knows."""
        ...


@runtime_checkable
class ReplansOnContact(Protocol):
    """A strategy that may ask for a replan on the step after its robot was in contact.

    The original replans every cycle while a robot receives messages; a strategy with
    this method says when such a replan is worth its cost (``belief``: the robot's map
    after the exchange).
    """

    def replan_on_contact(self, belief: BeliefGrid) -> bool:
        """Whether the robot, linked at the last exchange, should replan now."""
        ...


@runtime_checkable
class ReplansWhen(Protocol):
    """A strategy that may ask for a replan at any step (a rendezvous deadline, a link that
    came or went), besides its ``replan_interval``."""

    def replan_now(self, step: int, position: tuple[float, float], links: tuple[str, ...]) -> bool:
        """Whether the robot, at ``position`` and linked with ``links``, should replan now."""
        ...


@runtime_checkable
class ChoosesSendOrder(Protocol):
    """A strategy that chooses which of its map its robot's radio sends first when a link
    cannot carry everything (``communication.priority: strategy``, docs/communication.md)."""

    def send_first(self) -> tuple[float, float] | None:
        """The point whose nearest cells go first (None: the channel's ``base_first``)."""
        ...


class PlanContext:
    """Configuration space and distance field of one robot, computed lazily once.

    Distance fields answer "how far is everything" (utilities, costs); ``plan_to``
    gives the path the robot follows to the goal it chose, from its planner.
    """

    def __init__(self, view: RobotView) -> None:
        self.view = view

    @cached_property
    def free_box(self) -> Box | None:
        """The bounding box of the robot's FREE cells (None if none), found once, inside its
        known area (``knowledge/known_area.py``)."""
        return free_box(self.view.belief, self.view.features)

    @cached_property
    def _passable(self) -> tuple[np.ndarray, Box | None]:
        if PRIOR.of(self.view) is None:
            cells = passable_cells(self.view.belief, self.view.clearance, self.free_box)
        else:
            planned = self.view.planning_map  # the prior fills what the belief does not know
            cells = passable_cells(planned, self.view.clearance, bbox(planned == FREE))
        ground = GROUND.of(self.view)  # ground classes it cannot cross (ground/)
        if ground is None or cells[1] is None:
            return cells
        passable = ground.passable(cells[0])
        return passable, bbox(passable)

    @property
    def passable(self) -> np.ndarray:
        """Known-free cells at least the robot's clearance from any known obstacle (on its
        planning map: with a prior, the prior's cells where its own map knows nothing)."""
        return self._passable[0]

    @property
    def passable_box(self) -> Box | None:
        """The bounding box of :attr:`passable` (None if no cell is), found once."""
        return self._passable[1]

    @cached_property
    def slowness(self) -> FloatArray | None:
        """Cost multipliers of the terrain the robot knows (``planning.costs``) and of the
        ground classes it crosses slowly (``ground/``); None while it knows no slow ground
        (or the run has neither): uniform costs."""
        terrain = slowness_of(TERRAIN.of(self.view))
        ground = GROUND.of(self.view)
        return terrain if ground is None else ground.slowness_with(terrain)

    @cached_property
    def search(self) -> PausedSearch | None:
        """The robot's own unbounded search over its passable box, run only as far as
        asked (``fields_staged``, ``field``); None with terrain costs (the weighted search
        cannot pause) or when the robot has no passable cell within snapping reach."""
        box = self.passable_box
        if self.slowness is not None or box is None:
            return None
        start = snap_to_passable(self.passable, self.view.position, MAX_SNAP)
        if start is None:
            return None
        search = PausedSearch(self.passable, start, box)
        remember_window(self.passable, search.window)  # box is bbox(passable): the planner's
        return search

    @cached_property
    def field(self) -> DistanceField:
        """Path costs from the robot to every passable cell it can reach."""
        search = self.search
        if search is None:
            return self.field_from(self.view.position)
        search.run_below(np.inf)
        return self._field_of(search)

    def _field_of(self, search: PausedSearch) -> DistanceField:
        """The search's arrays as a field (shared: they change as the search goes on)."""
        window = search.window
        shape = (int(self.passable.shape[0]), int(self.passable.shape[1]))
        costs = search.dist.reshape(-1, window.wp)
        return DistanceField(shape, search.start, window.origin, costs, search.pred)

    def field_from(self, position: tuple[float, float], limit: float = np.inf) -> DistanceField:
        """Path costs on this robot's map from ``position`` (the robot's own, or a
        teammate's), up to ``limit``."""
        return distance_field(
            self.passable, position, limit=limit, slowness=self.slowness, box=self.passable_box
        )

    def fields_growing(self, first_limit: float) -> Iterator[tuple[float, DistanceField]]:
        """(horizon, field): distance fields bounded by a cost horizon that doubles,
        ending unbounded (horizon inf).

        A strategy that wants the nearest of something stops at the first field
        that holds what it needs; the late-exploration cost of a whole-map search is
        then paid only when nothing is near.
        """
        limit = max(first_limit, 1.0)
        extent = sum(self.view.belief.shape)
        while limit < extent:
            yield limit, self.field_from(self.view.position, limit)
            limit *= 2
        yield np.inf, self.field

    def fields_staged(self, first_bound: float) -> Iterator[tuple[float, DistanceField, float]]:
        """(horizon, field, final_below): the robot's own field searched out to a cost
        horizon that doubles, ending with the whole field (horizon inf). The field's costs
        below ``final_below`` are final, the others count as unreached; every cell not
        reached costs at least ``horizon``.

        One search pauses at each horizon and goes on from there (``planning.dial``;
        ``final_below`` = horizon), so a strategy that stops at the first field holding
        what it needs pays only for the cells below that horizon. With terrain costs the
        fields of :meth:`fields_growing` (each holds final costs only: ``final_below`` inf).
        """
        search = self.search
        if search is None:
            for limit, field in self.fields_growing(first_bound):
                yield limit, field, np.inf
            return
        bound = max(first_bound, 1.0)
        while not search.finished:
            search.run_below(bound)
            yield search.final_below, self._field_of(search), search.final_below
            bound *= 2
        yield np.inf, self.field, np.inf

    def plan_to(self, row: int, col: int) -> FloatArray:
        """The path the robot follows to cell (row, col): from its planner, if it has one.

        Without a planner the path is the distance field's (the same length as ``astar``).
        Empty (0, 2) if the cell cannot be reached.
        """
        planner = self.view.planner
        if planner is None:
            return self.field.path_to(row, col)
        if self.slowness is None:
            return planner.plan(self.passable, self.view.position, (row, col))
        return planner.plan(self.passable, self.view.position, (row, col), self.slowness)

    def topology(self, spacing: int = 10) -> TopologicalMap:
        """The topological map (skeleton, nodes, regions) of the robot's passable cells.

        A robot with the ``topological`` planner gets its planner's map (rebuilt only when
        its map changed enough); otherwise a build from the shared cache, ``spacing`` cells
        between nodes. Role-based strategies pick rendezvous points from its ``junctions``.
        """
        planner = self.view.planner
        if isinstance(planner, TopologicalPlanner):
            return planner.current_map(self.passable)
        return shared_map(self.passable, spacing)

    def planner_info(self) -> dict[str, Any]:
        """What the robot's planner adds to a decision's ``info`` (e.g. its ``skeleton``)."""
        planner = self.view.planner
        return dict(planner.info()) if planner is not None else {}

    def path_towards(self, x: float, y: float) -> FloatArray:
        """Path to the reachable cell nearest (straight-line) to world point (x, y)."""
        row, col = nearest_reached(self.field.costs, float(x), float(y))
        if row < 0:
            return np.zeros((0, 2))
        return self.plan_to(row, col)


def plan_context(view: RobotView) -> PlanContext:
    """The planning helpers for ``view``, each computed at most once."""
    return PlanContext(view)


def heading_for(context: PlanContext, point: tuple[float, float], **fields: Any) -> Decision:
    """A decision to follow the path towards ``point`` (as near as the robot's map lets it
    get), its goal the path's end (where the robot stands if there is no path);
    ``fields`` are the decision's other fields (``done``, ``info``, ``payload``)."""
    path = context.path_towards(*point)
    goal = (float(path[-1, 0]), float(path[-1, 1])) if len(path) else context.view.position
    return Decision(path=path, goal=goal, **fields)


def given_up_of(strategy: object) -> BoolGrid | None:
    """The frontier cells a strategy has tried in vain and given up, if it says (an
    optional ``given_up`` attribute, as ``frontier`` and the strategies built on it have):
    run health does not count them as frontier the robot could still explore."""
    grid = getattr(strategy, "given_up", None)
    return grid if isinstance(grid, np.ndarray) else None


HOME_TOLERANCE = 1.5  # cells: a done robot this close to its home point stays put
# Why a robot is done (``Decision.info["reason"]``): only NO_FRONTIER lets the decide phase
# try a smaller clearance first (``strategies/relax.py``); the others are the strategy's choice.
NO_FRONTIER = "no reachable frontier"
GOAL_MET = "mission complete"


def return_to_base(
    view: RobotView,
    context: PlanContext,
    home: tuple[float, float] | None = None,
    reason: str = NO_FRONTIER,
) -> Decision:
    """Nothing left to explore: head for the base station (as near as it can get) and stay.

    ``home`` is where an earlier call found the robot could get; a robot already
    there stays idle without searching the map again. ``reason`` says why it is done
    (``Decision.info["reason"]``).
    """
    if home is not None and np.hypot(*np.subtract(view.position, home)) <= HOME_TOLERANCE:
        return Decision(goal=home, done=True, info={"reason": reason})
    info = {**context.planner_info(), "reason": reason}
    return heading_for(context, view.base_position, done=True, info=info)
