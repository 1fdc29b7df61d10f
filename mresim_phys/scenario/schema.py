"""Scenario schema (phase 0, input): the pydantic models behind the YAML contract.

Pure: no file I/O here (``readers.py`` reads files, ``load.py`` turns a file into a
validated :class:`Scenario`). Every model forbids unknown keys, so a typo at any
depth is an error naming its field path. ``team`` holds the defaults every robot
inherits; a robot entry may override any of them (nested ``sensor`` keys merge). The run's
settings (``stop``, ``simulation``, ``render``, ``metrics``) are in ``run_specs.py``, the
events' union in ``event_union.py``; pydantic and the standard library only, all of them.
"""

from __future__ import annotations

import re
from typing import Annotated, Any, Literal

from pydantic import (
    AfterValidator,
    Field,
    field_validator,
    model_validator,
)

from mresim_phys.clocks.spec import ClockSpec
from mresim_phys.comms.radio_params import RadioSpec
from mresim_phys.faults.spec import FaultsSpec
from mresim_phys.ground.spec import Factor, GroundSpec, check_team_crosses
from mresim_phys.localization.spec import LocalizationSpec
from mresim_phys.scenario.event_union import EventList
from mresim_phys.scenario.hierarchy import check_hierarchy
from mresim_phys.scenario.maps import MapSpec, PriorSpec
from mresim_phys.scenario.run_specs import MetricsSpec, RenderSpec, SimulationSpec, StopSpec
from mresim_phys.strict import Strict
from mresim_phys.world.element_params import (
    DoorParams,
    ObstacleParams,
    RandomDebrisParams,
    TerrainSpec,
)
from mresim_phys.world.event_params import FailParams

Point = tuple[float, float]
MAX_RANGE = 100_000.0  # cells: sensor and radio ranges (a 1000x map diagonal is far less)
MAX_BODY = 1000.0  # cells: speed per step, body radius, planner margins
NAME_PATTERN = re.compile(r"[A-Za-z0-9_.-]*[A-Za-z0-9_][A-Za-z0-9_.-]*")  # never '.' or '..'
MAX_NAME = 64  # characters: a name becomes part of folder and file names
NAME_RULE = f"1 to {MAX_NAME} letters, digits, '_', '.' or '-', not only dots"


def check_name(name: str) -> str:
    """A scenario or robot name: it names folders and files, so it cannot leave them."""
    if len(name) > MAX_NAME or not NAME_PATTERN.fullmatch(name):
        raise ValueError(f"a name is made of {NAME_RULE} (it names output folders and files)")
    return name


Name = Annotated[str, AfterValidator(check_name)]


def shorthand(key: str, value: Any) -> Any:
    """A bare string ``x`` stands for ``{key: x}`` (``strategy: frontier``, ``model: disk``)."""
    return {key: value} if isinstance(value, str) else value


class PluginSpec(Strict):
    """A plugin chosen by registry name (or ``package.module:Class``) with its params."""

    name: str = Field(description="Registry name, or package.module:Class.")
    params: dict[str, Any] = Field(
        default_factory=dict, description="The plugin's own parameters (see below)."
    )

    @model_validator(mode="before")
    @classmethod
    def _from_name(cls, value: Any) -> Any:
        return shorthand("name", value)


class ChannelSpec(RadioSpec):
    """A radio channel: its model chosen by registry name, with its params, link losses and
    the radio options of :class:`~mresim_phys.comms.radio_params.RadioSpec`."""

    model: str = Field("disk", description="Comm model name (or package.module:Class).")
    params: dict[str, Any] = Field(
        default_factory=dict, description="The model's own parameters (see below)."
    )
    dropout: float = Field(
        0.0, ge=0, le=1, description="Probability that a link is lost, per link and step."
    )

    @model_validator(mode="before")
    @classmethod
    def _from_name(cls, value: Any) -> Any:
        return shorthand("model", value)


class ControlSpec(ChannelSpec):
    """The long-range, low-bandwidth control channel: teammate records only, no maps."""

    range: float = Field(
        500.0, ge=0, le=MAX_RANGE, description="Every agent's range (cells) on the control channel."
    )


class CommSpec(ChannelSpec):
    """The main channel (maps and teammate records) and an optional control channel."""

    maps: Literal["delta", "full"] = Field(
        "delta",
        description="Maps sent as changes since the pair last met, or whole grids each time.",
    )
    control: ControlSpec | None = Field(
        None, description="Optional control channel: {model, params, range, dropout}."
    )


class BeamSpec(Strict):
    """A laser's beam model (``world/beam.py``, docs/sensing.md): each ray reads a hit, a
    short return, no return or a random return, with these weights, or is lost."""

    z_hit: float = Field(1.0, ge=0, le=1, description="Weight of a hit: the true distance + noise.")
    z_short: float = Field(
        0.0, ge=0, le=1, description="Weight of a short return: something unmapped in the way."
    )
    z_max: float = Field(0.0, ge=0, le=1, description="Weight of no return (a max-range reading).")
    z_rand: float = Field(0.0, ge=0, le=1, description="Weight of a uniform random reading.")
    sigma_hit: float = Field(
        0.0, ge=0, le=MAX_RANGE, description="Gaussian noise (cells) of a hit's distance."
    )
    lambda_short: float = Field(
        0.1, gt=0, le=1000, description="Rate (per cell) of a short return's exponential."
    )
    dropout: float = Field(0.0, ge=0, lt=1, description="Probability that a ray is lost.")
    max_free: float | None = Field(
        None,
        ge=0,
        le=MAX_RANGE,
        description=(
            "Cells a no-return ray marks free (null: the whole range; 0: none, the ray is"
            " left out of the free area)."
        ),
    )

    speckle: float | None = Field(
        None,
        gt=0,
        le=MAX_RANGE,
        description=(
            "The robot's speckle filter (cells): a return farther than this from every"
            " return within speckle_window rays is left out (null: off)."
        ),
    )
    speckle_window: int = Field(2, ge=1, le=64, description="Rays each side the filter compares.")

    @model_validator(mode="after")
    def _weights_sum_to_one(self) -> BeamSpec:
        total = self.z_hit + self.z_short + self.z_max + self.z_rand
        if abs(total - 1.0) > 1e-6:
            raise ValueError(
                "the weights z_hit + z_short + z_max + z_rand must sum to 1 (a reading is one"
                f" of the four kinds); these sum to {total:g}"
            )
        return self


class SensorSpec(Strict):
    """A planar laser scanner: ``rays`` rays evenly over ``fov_deg`` centred on the heading."""

    range: float = Field(100.0, gt=0, le=MAX_RANGE, description="Maximum range in cells.")
    fov_deg: float = Field(180.0, gt=0, le=360, description="Field of view in degrees.")
    rays: int = Field(181, ge=2, le=4096, description="Number of rays (181 = 1 degree apart).")
    noise_std: float = Field(
        0.0, ge=0, le=MAX_RANGE, description="Gaussian range noise (cells); 0 = exact."
    )
    safe_fraction: float = Field(
        0.1, gt=0, le=1, description="Safe space = rays clipped to this fraction of the range."
    )
    beam: BeamSpec | None = Field(
        None,
        description=(
            "Beam model of the readings: {z_hit, z_short, z_max, z_rand, sigma_hit,"
            " lambda_short, dropout, max_free, speckle, speckle_window} (null: exact"
            " distances; docs/sensing.md)."
        ),
    )

    @model_validator(mode="after")
    def _one_noise(self) -> SensorSpec:
        if self.beam is not None and self.noise_std > 0:
            raise ValueError(
                "a sensor with a beam model takes its range noise from beam.sigma_hit; set"
                " noise_std to 0 (or leave it out) and give the noise there"
            )
        return self


class RobotParams(Strict):
    """Everything a robot can have; ``team`` gives the defaults, a robot may override."""

    speed: float = Field(3.0, gt=0, le=MAX_BODY, description="Cells moved at most per step.")
    radius: float = Field(2.0, gt=0, le=MAX_BODY, description="Body radius in cells.")
    sensor: SensorSpec = Field(default_factory=SensorSpec)
    comm_range: float = Field(
        150.0, ge=0, le=MAX_RANGE, description="Communication range in cells."
    )
    comm_power_dbm: float | None = Field(
        None, description="path_loss: signal (dBm) at comm_range; None = the model's default."
    )
    role: Literal["explorer", "relay"] = Field("explorer", description="Team role.")
    strategy: PluginSpec = Field(
        default_factory=lambda: PluginSpec(name="frontier"),
        description="Exploration strategy: a name or {name, params}.",
    )
    wall_margin: float = Field(
        1.0,
        ge=0,
        le=MAX_BODY,
        description="Extra clearance (cells) the planner keeps from known walls.",
    )
    planner: PluginSpec = Field(
        default_factory=lambda: PluginSpec(name="astar"),
        description="Path planner (astar, jps or topological): a name or {name, params}.",
    )
    localization: LocalizationSpec | None = Field(
        None,
        description=(
            "Odometry drift and pose corrections: {odometry: {alpha}, corrections: [...]}"
            " (null: the robot knows its exact pose)."
        ),
    )
    crosses: dict[str, Factor] | None = Field(
        None,
        description=(
            "Its speed factor on each ground class it crosses otherwise than the class's"
            " default, in [0, 1] (0: it cannot enter); docs/ground.md."
        ),
    )
    clock: ClockSpec | None = Field(
        None,
        description=(
            "Its own clock: {act_every, phase, decision_period, compute_delay, scan_period}"
            " (null: it acts, decides and scans on every step; docs/clocks.md)."
        ),
    )


class RobotSpec(RobotParams):
    """One robot: its name, start pose and any overridden team fields."""

    name: Name = Field(description=f"Unique robot name: {NAME_RULE}.")
    start: Point = Field(description="Start position [x, y] in cells (x = column, y = row).")
    heading_deg: float = Field(0.0, description="Start heading; 0 = +x, 90 = +y (down).")
    parent: str | None = Field(
        None,
        description=(
            "Its parent in the team's hierarchy: 'base' or a robot's name (null: none). Drawn"
            " by the hierarchy video layer; leader_follower keeps every robot in its parent's"
            " range."
        ),
    )


class BaseStationSpec(Strict):
    """The static base station collecting what reaches it."""

    position: Point = Field(description="[x, y] in cells.")
    comm_range: float = Field(
        150.0, ge=0, le=MAX_RANGE, description="Communication range in cells."
    )
    comm_power_dbm: float | None = Field(
        None, description="path_loss: signal (dBm) at comm_range; None = the model's default."
    )


class Scenario(Strict):
    """A whole run: map, base station, team, communication and events."""

    name: Name = Field(description=f"Names the output folder: {NAME_RULE}.")
    seed: int = Field(0, ge=0, le=2**63 - 1, description="Seeds every random stream of the run.")
    steps: int = Field(3000, ge=1, description="Hard cap on the number of steps.")
    units: Literal["cells", "m"] = Field(
        "cells",
        description="cells: positions, lengths and speeds in cells and cells per step;"
        " m: in metres and metres per second, positions in the map frame (origin applied,"
        " y up), headings counter-clockwise (needs dt and a map resolution).",
    )
    dt: float | None = Field(
        None,
        gt=0,
        le=3600,
        description="Seconds per step: results are given in seconds (and metres, with a"
        " map resolution) beside steps (and cells). Needed by units: m.",
    )
    stop: StopSpec = Field(default_factory=StopSpec, description="Early stop rules.")
    map: MapSpec = Field(description="The ground-truth map.")
    base_station: BaseStationSpec = Field(description="Where the base station stands.")
    team: RobotParams = Field(default_factory=RobotParams, description="Defaults for every robot.")
    robots: list[RobotSpec] = Field(min_length=1, description="The team, at least one robot.")
    communication: CommSpec = Field(
        default_factory=CommSpec, description="Communication model and its params."
    )
    simulation: SimulationSpec = Field(
        default_factory=SimulationSpec, description="How the cycle runs."
    )
    render: RenderSpec = Field(
        default_factory=RenderSpec, description="Video, pictures, run log and plots."
    )
    metrics: MetricsSpec = Field(
        default_factory=MetricsSpec, description="Optional columns of metrics.csv."
    )
    events: EventList = Field(
        default_factory=list,
        description="Scheduled events (robot failures, blackouts, ...): see 'events' below.",
    )
    obstacles: list[ObstacleParams] = Field(
        default_factory=list,
        description="Moving obstacles (people, carts): shape, motion, life span; see below.",
    )
    doors: list[DoorParams] = Field(
        default_factory=list,
        description="Doors that close and open (by close / open events or by a cycle).",
    )
    random_debris: RandomDebrisParams | None = Field(
        None, description="Rubble falling at random steps and places (null: none)."
    )
    terrain: TerrainSpec | None = Field(
        None, description="Variable terrain: a speed factor per cell (null: open floor)."
    )
    prior: PriorSpec | None = Field(
        None, description="A map robots know before the mission, maybe out of date (null: none)."
    )
    faults: FaultsSpec | None = Field(
        None,
        description="Random failures, battery, hazard zones, out-of-contact rule (null: none).",
    )
    ground: GroundSpec | None = Field(
        None,
        description="Ground classes (rubble, stairs, water...) robots cross at their own factors.",
    )

    @model_validator(mode="before")
    @classmethod
    def _apply_team_defaults(cls, data: Any) -> Any:
        if not isinstance(data, dict) or not isinstance(data.get("robots"), list):
            return data
        team = data.get("team") or {}
        if not isinstance(team, dict):
            return data
        robots = [_inherit(team, r) if isinstance(r, dict) else r for r in data["robots"]]
        return {**data, "robots": robots}

    @model_validator(mode="after")
    def _snapshots_within_steps(self) -> Scenario:
        late = [s for s in self.render.snapshots if s > self.steps]
        if late:
            raise ValueError(
                f"render.snapshots: step{'s' if len(late) > 1 else ''} {late} past the step cap"
                f" (steps: {self.steps}); give snapshot steps from 0 to {self.steps}"
            )
        return self

    @model_validator(mode="after")
    def _listed_robots_exist(self) -> Scenario:
        """Robot lists of the prior map and of the fault models name robots of the team."""
        names = [r.name for r in self.robots]
        lists = list(self.faults.robot_lists()) if self.faults is not None else []
        if self.prior is not None:
            lists.insert(0, ("prior.robots", self.prior.robots))
        for where, robots in lists:
            unknown = [n for n in robots if n not in names] if robots != "all" else []
            if unknown:
                raise ValueError(
                    f"{where}: no robot called {', '.join(map(repr, unknown))}"
                    f" (robots: {', '.join(names)}); list robot names or give 'all'"
                )
        return self

    @model_validator(mode="after")
    def _one_failure_per_part_and_step(self) -> Scenario:
        seen: dict[tuple[str, str, int], int] = {}
        for i, event in enumerate(self.events):
            if isinstance(event, FailParams):
                key = (event.fail, event.part, event.step)
                if key in seen:
                    raise ValueError(
                        f"events[{seen[key]}] and events[{i}] both fail the {event.part} of"
                        f" robot {event.fail!r} at step {event.step}; give one event per part,"
                        " robot and step"
                    )
                seen[key] = i
        return self

    @model_validator(mode="after")
    def _hierarchy(self) -> Scenario:
        check_hierarchy(self.robots)
        return self

    @model_validator(mode="after")
    def _crosses_name_classes(self) -> Scenario:
        check_team_crosses(self.ground, [(r.name, r.crosses) for r in self.robots if r.crosses])
        return self

    @field_validator("robots")
    @classmethod
    def _unique_names(cls, robots: list[RobotSpec]) -> list[RobotSpec]:
        names = [r.name for r in robots]
        dupes = sorted({n for n in names if names.count(n) > 1})
        if dupes:
            raise ValueError(f"robot names must be unique; repeated: {dupes}")
        if "base" in names:
            raise ValueError("'base' is the base station's name; give the robot another name")
        return robots


def _inherit(team: dict[str, Any], robot: dict[str, Any]) -> dict[str, Any]:
    """Robot fields over team defaults; a robot's ``sensor``, ``localization``, ``clock``
    and ``crosses`` dicts merge into the team's key by key."""
    merged = {**team, **robot}
    for key in ("sensor", "localization", "clock", "crosses"):
        theirs, own = team.get(key), robot.get(key)
        if isinstance(theirs, dict) and isinstance(own, dict):
            merged[key] = {**theirs, **own}
    return merged
