"""What each robot discovered (phase 7, a per-robot feature): overlap and workload balance.

A run with ``metrics.team: true`` (or naming one of the columns below) gives every robot
the feature ``discovery``. A cell counts as *discovered* by a robot when the robot's own
scans turn it FREE in its map (a cell it got from a teammate's map is not its discovery):
the cells FREE in its map after its turn that were not before, within the box its scans
can reach this step. Team-wide, each cell counts the robots that discovered it; in robot
order, a robot's discovery is *first* when no robot had discovered the cell before, and
*again* when it is the second robot to. So:

* ``overlap`` = the team's *again* / the team's *first*: the share of the discovered cells
  that two or more robots discovered (double sensing: robots exploring the same space
  before they knew of each other's maps);
* ``workload_cv`` = the coefficient of variation (standard deviation / mean) of the
  robots' *first* counts: 0 when every robot added the same number of cells to what the
  team knows, higher when a few did the work;
* ``discovered_<robot>`` = its *first* count so far.

The value ``[discovered, first, again]`` is logged in each robot's line of the run log, so
a replay recomputes the columns; the viewer's hover row shows the three. summary.json's
``team`` object (``output/team.py``) gives them at the end with the longest path.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from mresim_phys.columns import column
from mresim_phys.features import RobotFeature
from mresim_phys.types import FREE, BeliefGrid, IntArray

if TYPE_CHECKING:
    from mresim_phys.agents import Robot
    from mresim_phys.metrics import StepRecord

TEAM_COLUMNS = ("overlap", "workload_cv", "discovered")


@dataclass(frozen=True)
class Discovered:
    """A robot's discoveries so far: cells it discovered, those first, those second."""

    discovered: int = 0
    first: int = 0
    again: int = 0


@dataclass
class Discovery:
    """A robot's discovery counters, the team's count per cell (shared by every robot of a
    run) and the cells of its turn not yet counted."""

    team: np.ndarray  # uint8 per cell: robots that discovered it (saturating at 255)
    discovered: int = 0
    first: int = 0
    again: int = 0
    before: tuple[tuple[int, int, int, int], np.ndarray] | None = (
        None  # its box at the turn's start
    )
    pending: IntArray = field(default_factory=lambda: np.zeros(0, dtype=np.intp))

    def watch(self, belief: BeliefGrid, position: tuple[float, float], reach: float) -> None:
        """Before a turn: keep where its map is FREE in the box its scans can reach."""
        rows, cols = belief.shape
        x, y = position
        r0, r1 = max(int(y - reach), 0), min(int(y + reach) + 2, rows)
        c0, c1 = max(int(x - reach), 0), min(int(x + reach) + 2, cols)
        self.before = ((r0, r1, c0, c1), belief[r0:r1, c0:c1] == FREE)

    def seen(self, belief: BeliefGrid) -> None:
        """After a turn: the cells its own scans turned FREE, to be counted."""
        if self.before is None:
            return
        (r0, r1, c0, c1), was = self.before
        new = (belief[r0:r1, c0:c1] == FREE) & ~was
        rr, cc = np.nonzero(new)
        self.pending = np.concatenate([self.pending, (rr + r0) * belief.shape[1] + cc + c0])
        self.before = None

    def count(self) -> None:
        """Count the pending cells against the team (in robot order, after every turn)."""
        cells, self.pending = self.pending, self.pending[:0]
        if len(cells) == 0:
            return
        flat = self.team.reshape(-1)
        held = flat[cells]
        self.discovered += len(cells)
        self.first += int(np.count_nonzero(held == 0))
        self.again += int(np.count_nonzero(held == 1))
        flat[cells] = np.minimum(held, 254) + 1


class DiscoveryFeature(RobotFeature[Discovery, Discovered]):
    """What a robot discovered (module docstring)."""

    key = "discovery"

    def value(self, state: Discovery) -> Discovered:
        """Its counts so far."""
        return Discovered(state.discovered, state.first, state.again)

    def encode(self, value: Discovered) -> Any:
        """``[discovered, first, again]``."""
        return [value.discovered, value.first, value.again]

    def decode(self, raw: Any) -> Discovered:
        """The logged list read back."""
        return Discovered(int(raw[0]), int(raw[1]), int(raw[2]))

    def hover(self, value: Discovered) -> Any:
        """The three, named."""
        return {"discovered": value.discovered, "first": value.first, "again": value.again}


DISCOVERY = DiscoveryFeature()


def give_discovery(robots: Sequence[Robot], shape: tuple[int, int]) -> None:
    """Every robot's counters, over one team grid of ``shape``."""
    team = np.zeros(shape, dtype=np.uint8)
    for robot in robots:
        robot.features[DISCOVERY.key] = Discovery(team)


def watch_discoveries(robot: Robot) -> Discovery | None:
    """Before the robot's turn: its counters, watching the box its scans can reach (None:
    the run does not count discoveries)."""
    state = DISCOVERY.state_of(robot.features)
    if state is not None:
        reach = robot.laser.range + robot.speed + 2.0
        state.watch(robot.belief, robot.believed_position, reach)
    return state


def count_discoveries(robots: Sequence[Robot]) -> None:
    """After the robots' turns: count each one's new cells, in robot order."""
    for robot in robots:
        state = DISCOVERY.state_of(robot.features)
        if state is not None:
            state.count()


def team_values(r: StepRecord) -> list[Discovered]:
    """The robots' discoveries at ``r``'s step ([] without the feature)."""
    return [v for v in (DISCOVERY.of(robot) for robot in r.robots) if v is not None]


def overlap_of(values: Sequence[Discovered]) -> float | None:
    """The share of the discovered cells two or more robots discovered."""
    first = sum(v.first for v in values)
    return sum(v.again for v in values) / first if first else (0.0 if values else None)


def workload_cv_of(values: Sequence[Discovered]) -> float | None:
    """Standard deviation / mean of the robots' first discoveries."""
    if not values:
        return None
    counts = np.array([v.first for v in values], dtype=float)
    mean = float(counts.mean())
    return float(counts.std()) / mean if mean > 0 else 0.0


@column("overlap", optional=True)
def overlap(r: StepRecord) -> float | None:
    """Share of the team's discovered cells that two or more robots discovered."""
    return overlap_of(team_values(r))


@column("workload_cv", optional=True)
def workload_cv(r: StepRecord) -> float | None:
    """Coefficient of variation of the robots' first discoveries (0: an even share)."""
    value = workload_cv_of(team_values(r))
    return None if value is None or math.isnan(value) else value


@column("discovered", per_robot=True, prefix="discovered", optional=True)
def discovered(r: StepRecord) -> list[int | None]:
    """Cells the robot discovered first so far."""
    values = [DISCOVERY.of(robot) for robot in r.robots]
    return [None if v is None else v.first for v in values]
