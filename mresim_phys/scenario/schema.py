"""Scenario schema (phase 0, input): the pydantic models behind the YAML contract.

Pure: no file I/O here (``readers.py`` reads files, ``load.py`` turns a file into a
validated :class:`Scenario`). Every model forbids unknown keys, so a typo at any
depth is an error naming its field path. ``team`` holds the defaults every robot
inherits; a robot entry may override any of them (nested ``sensor`` keys merge).
"""

from __future__ import annotations

import re
from functools import lru_cache
from typing import Annotated, Any, Literal, Union

from pydantic import (
    AfterValidator,
    Discriminator,
    Field,
    SerializeAsAny,
    Tag,
    TypeAdapter,
    ValidatorFunctionWrapHandler,
    WrapValidator,
    field_validator,
    model_validator,
)

from mresim_phys.faults.spec import FaultsSpec
from mresim_phys.scenario.hierarchy import check_hierarchy
from mresim_phys.scenario.maps import MapSpec, PriorSpec
from mresim_phys.strict import Strict
from mresim_phys.world.debris import RandomDebrisParams
from mresim_phys.world.doors import DoorParams
from mresim_phys.world.events import EVENTS, EventParams, FailParams
from mresim_phys.world.obstacles import ObstacleParams
from mresim_phys.world.terrain import TerrainSpec

Point = tuple[float, float]
MAX_RANGE = 100_000.0  # cells: sensor and radio ranges (a 1000x map diagonal is far less)
MAX_BODY = 1000.0  # cells: speed per step, body radius, planner margins
NAME_PATTERN = re.compile(r"[A-Za-z0-9_.-]*[A-Za-z0-9_][A-Za-z0-9_.-]*")  # never '.' or '..'
MAX_THREADS = 1024  # simulation.threads: more than any machine's cores, fewer than a typo's
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


class ChannelSpec(Strict):
    """A radio channel: its model chosen by registry name, with its params and link losses."""

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


class StopSpec(Strict):
    """Optional early stop rules (the run also stops at ``steps``)."""

    explored: float | None = Field(None, gt=0, le=1, description="Team-known fraction.")
    known_at_base: float | None = Field(None, gt=0, le=1, description="Base-known fraction.")
    all_done: bool = Field(True, description="Stop when every robot is done or failed.")
    stalled_for: int | None = Field(
        300,
        ge=1,
        le=1_000_000,
        description=(
            "Stop when neither explored nor known at base has gained stalled_gain in this"
            " many steps (stop reason 'stalled'); null = never."
        ),
    )
    stalled_gain: float = Field(
        0.001,
        ge=0,
        le=1,
        description="Smallest gain (fraction of the free area) that counts as progress.",
    )


class StartJitterSpec(Strict):
    """Per-robot random offsets of the declared starts, drawn from the seed."""

    position: float = Field(
        0.0, ge=0, le=1000, description="Largest shift of a start (cells, uniform in a disk)."
    )
    heading_deg: float = Field(
        0.0, ge=0, le=180, description="Largest turn of a start heading (degrees, uniform, +-)."
    )


class SimulationSpec(Strict):
    """How the cycle runs."""

    scan: Literal["point", "step"] = Field(
        "point", description="Scan after every path point (as the original) or once per step."
    )
    robots_block: bool = Field(False, description="Robots block each other's rays and motion.")
    multi_hop: bool = Field(
        True, description="Information flows along chains of linked agents within a step."
    )
    presume_lost_after: int = Field(
        200,
        ge=1,
        description="Steps without news after which a strategy sees a teammate as presumed lost.",
    )
    vary_with_seed: bool = Field(
        True,
        description=(
            "The seed varies the run: initial random-walk steps, auction tie-breaks and"
            " start_jitter; false makes every seed give the same run (noise and dropouts"
            " you turn on still draw from the seed)."
        ),
    )
    start_jitter: StartJitterSpec = Field(
        default_factory=StartJitterSpec,
        description="Random shifts of the robots' starts (position and heading) per seed.",
    )
    belief: Literal["auto", "latest", "grow"] = Field(
        "auto",
        description=(
            "How robots' maps change: 'latest' (each cell holds its latest observation: a"
            " scan overwrites what it sees, an exchange keeps the newer observation, ties go"
            " to the obstacle), 'grow' (known cells only grow: unknown < free < obstacle, as"
            " the original), or 'auto': latest when the world can change (obstacles, doors,"
            " debris, collapse or cells events), grow otherwise."
        ),
    )
    paired: bool = Field(
        False,
        description=(
            "Also run the same scenario and seed with every fault switched off (no fail"
            " events) as a baseline, and write robustness.json (as `mresim run --paired`)."
        ),
    )
    threads: Annotated[int, Field(ge=1, le=MAX_THREADS)] | Literal["auto"] = Field(
        1,
        description=(
            "Threads (a number, or auto = one per core) for the robots' replans, moves,"
            " scans and map updates within a step; 1 = one robot after another. The results"
            " are the same."
        ),
    )


class RenderSpec(Strict):
    """What a run leaves besides its metrics: video, pictures, run log, plots."""

    video: bool | str = Field(
        False, description="Write a video: true = videos/<name>-seed<seed>.mp4, or a path."
    )
    fps: float = Field(20.0, gt=0, le=240, description="Video frames per second.")
    every: int = Field(1, ge=1, description="One video frame every this many steps.")
    layers: str = Field(
        "default", description="Layers to draw, e.g. 'default', 'all', 'default,B:free_space'."
    )
    scale: float = Field(1.0, gt=0, le=8, description="Frame scale (2 = twice the map size).")
    snapshots: list[Annotated[int, Field(ge=0)]] = Field(
        default_factory=list,
        description="Steps at which to write PNG frames (0 .. steps).",
    )
    final_png: bool = Field(True, description="Write final.png of the last step.")
    log: bool = Field(True, description="Write the run log (for replay without re-running).")
    plots: bool = Field(True, description="Write plots at the end (needs the plot extra).")


class MetricsSpec(Strict):
    """What ``metrics.csv`` holds beyond its default columns."""

    columns: list[str] = Field(
        default_factory=list,
        description="Optional metric columns written after the default ones, in this order:"
        " a column's name (robots_done, base_links, robot_base_link, or one a package"
        " registers) or package.module:Class; see docs/metric-columns.md.",
    )


def event_kind(value: Any) -> str | None:
    """Which registered event a YAML entry is: the first event name among its keys."""
    if isinstance(value, EventParams):
        return next((n for n in EVENTS.names() if isinstance(value, EVENTS.get(n).Params)), None)
    if isinstance(value, dict):
        return next((n for n in EVENTS.names() if n in value), None)
    return None


@lru_cache(maxsize=8)
def event_adapter(names: tuple[str, ...]) -> TypeAdapter[Any]:
    """A validator of one ``events[i]`` entry: one tagged member per registered event's
    ``Params`` (``names``: the registry's event names when it is asked)."""
    members = tuple(Annotated[EVENTS.get(n).Params, Tag(n)] for n in names)
    union: Any = Annotated[
        Union[members],  # noqa: UP007 (a union built from a tuple of types)
        Discriminator(
            event_kind,
            custom_error_type="unknown_event",
            custom_error_message="an event needs one of the keys "
            + ", ".join(repr(n) for n in names),
        ),
    ]
    return TypeAdapter(union)


def validate_event(value: Any, handler: ValidatorFunctionWrapHandler) -> EventParams:
    """One ``events[i]`` entry validated by the ``Params`` of its event, looked up in the
    registry now (an event registered in code or by an entry point since the last
    scenario is known at once; nothing is rebuilt)."""
    if isinstance(value, EventParams):
        return value
    event: EventParams = event_adapter(tuple(EVENTS.names())).validate_python(value)
    return event


EventList = list[SerializeAsAny[Annotated[EventParams, WrapValidator(validate_event)]]]


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
    """Robot fields over team defaults; a robot's ``sensor`` dict merges into the team's."""
    merged = {**team, **robot}
    team_sensor, robot_sensor = team.get("sensor"), robot.get("sensor")
    if isinstance(team_sensor, dict) and isinstance(robot_sensor, dict):
        merged["sensor"] = {**team_sensor, **robot_sensor}
    return merged
