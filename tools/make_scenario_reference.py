"""Write docs/scenario-reference.md from the scenario schema and the plugin registries.

Run ``python tools/make_scenario_reference.py`` after changing a schema model or a
plugin's params; tests/test_docs.py fails when the committed file is out of date.
"""

from __future__ import annotations

import sys
from pathlib import Path
from types import UnionType
from typing import Annotated, Any, Literal, Union, get_args, get_origin

from pydantic import BaseModel
from pydantic_core import PydanticUndefined

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from mresim_phys import COMM_MODELS, STRATEGIES  # noqa: E402
from mresim_phys.clocks.spec import ClockSpec, DelaySpec  # noqa: E402
from mresim_phys.comms import radio_params as radio  # noqa: E402
from mresim_phys.faults import spec as fault_spec  # noqa: E402
from mresim_phys.ground.spec import GroundRegion, GroundSpec  # noqa: E402
from mresim_phys.localization import spec as localization  # noqa: E402
from mresim_phys.planning import PLANNERS  # noqa: E402
from mresim_phys.scenario import run_specs, schema  # noqa: E402
from mresim_phys.scenario.maps import PriorSpec  # noqa: E402
from mresim_phys.scenario.yamlfile import MAX_ALIAS_VALUES, MAX_YAML_BYTES  # noqa: E402
from mresim_phys.strict import MAX_FLOAT, MAX_INT, UNIT_BOUNDS, bounds_text  # noqa: E402
from mresim_phys.world import element_params as elements  # noqa: E402
from mresim_phys.world import shapes  # noqa: E402
from mresim_phys.world.event_catalog import EVENTS  # noqa: E402

SECTIONS: list[tuple[str, type[BaseModel]]] = [
    ("Scenario (top level)", schema.Scenario),
    ("map", schema.MapSpec),
    ("base_station", schema.BaseStationSpec),
    ("team and each robot", schema.RobotParams),
    ("robots[i] (adds to the team fields)", schema.RobotSpec),
    ("sensor", schema.SensorSpec),
    ("sensor.beam", schema.BeamSpec),
    ("clock (team or robots[i])", ClockSpec),
    ("clock.compute_delay", DelaySpec),
    ("communication", schema.CommSpec),
    ("communication.shadowing (either channel)", radio.ShadowingSpec),
    ("communication.bursts (either channel)", radio.BurstSpec),
    ("strategy and planner", schema.PluginSpec),
    ("stop", run_specs.StopSpec),
    ("simulation", run_specs.SimulationSpec),
    ("simulation.start_jitter", run_specs.StartJitterSpec),
    ("render", run_specs.RenderSpec),
    ("metrics", run_specs.MetricsSpec),
    ("metrics.budget", run_specs.BudgetSpec),
    ("obstacles[i]", elements.ObstacleParams),
    ("obstacles[i].shape: one of", shapes.CircleShape),
    ("", shapes.BoxShape),
    ("", shapes.PolygonShape),
    ("obstacles[i].motion: one of", elements.WaypointsMotion),
    ("", elements.RandomWalkMotion),
    ("", elements.StillMotion),
    ("doors[i]", elements.DoorParams),
    ("random_debris", elements.RandomDebrisParams),
    (
        "regions (collapse, random_debris.region, faults.hazards[i].region): one of",
        shapes.BoxRegion,
    ),
    ("", shapes.CircleRegion),
    ("", shapes.PolygonRegion),
    ("", shapes.MaskRegion),
    ("terrain", elements.TerrainSpec),
    ("terrain.regions[i]", elements.TerrainRegion),
    ("ground", GroundSpec),
    ("ground.regions[i]", GroundRegion),
    ("prior", PriorSpec),
    ("faults", fault_spec.FaultsSpec),
    ("faults.random[i]", fault_spec.RandomFaultSpec),
    ("faults.battery", fault_spec.BatterySpec),
    ("faults.hazards[i]", fault_spec.HazardSpec),
    ("localization (team or robots[i])", localization.LocalizationSpec),
    ("localization.odometry", localization.OdometrySpec),
    ("localization.corrections[i], kind: base", localization.BaseFix),
    ("localization.corrections[i], kind: beacons", localization.BeaconsFix),
    ("localization.corrections[i], kind: teammate", localization.TeammateFix),
    ("localization.corrections[i], kind: scan_matching", localization.ScanMatchFix),
]
NOTES = {
    "communication.shadowing (either channel)": (
        "Added to the signal of a model that has one (path_loss): a seeded field with"
        " correlation exp(-(h/length)^2), sigma_db per link, fast fading per step"
        " (docs/communication.md, 'Radio links'). Streams `shadowing-<channel>` and"
        " `fading-<channel>`."
    ),
    "communication.bursts (either channel)": (
        "A Gilbert-Elliott chain per agent pair, from its stationary state; stream"
        " `bursts-<channel>`. The long-run loss is pi_bad * loss_bad + (1 - pi_bad) *"
        " loss_good with pi_bad = good_to_bad / (good_to_bad + bad_to_good)."
    ),
    "sensor.beam": (
        "The laser beam model: each ray reads a hit (the true distance plus Gaussian noise),"
        " a short return, no return or a random return, with the weights z_hit, z_short,"
        " z_max, z_rand (summing to 1), or is lost (dropout); draws from the robot's stream"
        " `sensing`. The robot maps by evidence (a cell is believed once two scans agree;"
        " a reading through a wall it knows frees nothing behind it). Not with noise_std."
        " Adds the metric column `noisy_readings`, the per-robot feature `readings` and"
        " summary.json's `readings` object; see [sensing.md](sensing.md)."
    ),
    "clock (team or robots[i])": (
        "A robot's own clock (a robot's block merges into the team's key by key). It acts"
        " (moves, decides, scans) on the steps t with t % act_every == phase and still"
        " communicates on every step; its strategy is asked at most once every"
        " decision_period steps and never while a plan waits; a plan takes effect"
        " compute_delay steps after it was asked (the robot follows its old path until"
        " then); it scans on a step at least scan_period steps after its last. A failure"
        " drops the waiting plan, a recovery starts the clock again on that step, and a"
        " caller's decision (`step(actions=...)`) waits for its next step."
        " Adds the metric column `decisions` and the per-robot feature `clock`; see"
        " [clocks.md](clocks.md)."
    ),
    "metrics": (
        "Optional columns, more milestone levels, success within a budget and the team's"
        " figures (overlap, workload balance, discoveries, longest path); see"
        ' [metric-columns.md](metric-columns.md), "The figures papers report".'
    ),
    "clock.compute_delay": (
        "An integer d (every plan waits d steps), or {min, max}: each plan waits a number"
        " of steps drawn uniformly from min to max (both included) from the robot's stream"
        " `compute-delay`."
    ),
    "localization (team or robots[i])": (
        "A robot with this block knows its pose only through its odometry and corrections:"
        " its map, plans, teammate record and strategy use the believed pose, its body,"
        " laser and radio the true one. A robot's own block merges into the team's key by"
        " key. Motion noise draws from the robot's stream `odometry`, correction noise from"
        " its stream `pose-fix` (docs/seeds.md). Adds the metric columns `pose_error`,"
        " `heading_error`, `pose_error_mean`, `pose_error_max` and summary.json's"
        " `localization` object;"
        " see [localization.md](localization.md)."
    ),
    "obstacles[i]": (
        "A moving obstacle's body is the cells whose centre lies inside its shape, standing"
        " where its centre is; it moves in the events phase and never overlaps a wall,"
        " another obstacle or a robot: when its next place is taken it waits that step"
        " (a random walker then draws a new heading). Random walks draw from the stream"
        " `obstacle/<name>` of the seed."
    ),
    "doors[i]": (
        "A closed door is a wall for rays, motion, line of sight, path loss and the truth"
        " grid: the cells its segment passes through (4-connected) and those within half"
        " its thickness. It changes on `close` / `open` events or cycles (`period`,"
        " `open_for`, from `offset`), and never closes on a robot: it waits, open, until"
        " its doorway is clear."
    ),
    "random_debris": (
        "Each step from `after` to `until`, a square piece falls with probability `rate`"
        " (draws from the stream `debris` of the seed), centred on a random cell of"
        " `region`. Rubble never lands on a robot: with `crush: avoid` its cells stay free;"
        " with `crush: fail` the robot is buried and fails."
    ),
    "terrain": (
        "A speed factor in (0, 1] per cell, from a greyscale `image` the size of the map"
        " (`factor = max(min_factor, value / 255)`: white 1, black `min_factor`) or from"
        " `regions` (other cells 1; where regions overlap the later wins). A robot's distance"
        " budget for a step is `speed * factor` of the cell under it at the start of the"
        " step. A robot learns the true factor of every cell its scans mark free (1 where"
        " it has not sensed the ground; known terrain is not exchanged between robots), and"
        " its distance fields and planners price a move as its octile length times the mean"
        " of `1 / factor` of its two cells; `jps` and `topological` plan with that cost-aware"
        " A* once the robot knows slow ground. The `terrain` video layer tints slow ground"
        " brown."
    ),
    "ground": (
        "Named ground classes (rubble, stairs, water, ...) with each class's default speed"
        " factor in [0, 1] (0: a robot cannot enter it), from a colour `image` the size of"
        " the map whose `legend` gives each class's colour [r, g, b] (other colours: floor)"
        " and/or `regions` drawn over it in order. A robot's `crosses` (team or robots[i])"
        " gives its own factor per class. Each robot plans over the cells it can cross,"
        " pricing slow ones by 1 / factor, moves at its factor of the class under it, and"
        " never enters a cell it cannot cross; it knows the class of every cell its map holds"
        " free (a cell's class travels with the cell). Ground no robot crosses is left out"
        " of the explorable area. The `ground` video layer shades each class in its colour;"
        " see [ground.md](ground.md)."
    ),
    "ground.regions[i]": (
        "One of `box`, `circle`, `polygon` or `mask`, as the regions above, with its class"
        " (`ground`)."
    ),
    "terrain.regions[i]": (
        "One of `box`, `circle`, `polygon` or `mask`, as the regions above, with its `factor`."
    ),
    "prior": (
        "A map (`map`: the keys of `map` above, a file of the map's size) that the listed"
        " robots know before the mission: the building plan, perhaps from before a collapse."
        " It is degraded once per run from the stream `prior` of the seed: each cell dropped"
        " (unknown) with probability `drop`, each kept cell flipped (free <-> wall) with"
        " probability `flip`. Prior cells are not observations: they never count as explored"
        " or known at the base and are never exchanged. A robot plans its paths and distance"
        " fields on its own map with the prior filling the cells it does not know, so a scan"
        " overrides the plan; its frontiers stay on its own map, and a robot whose sensed map"
        " blocks its path replans. The `prior` video layer tints blue the cells the prior"
        " holds as walls where the truth is free."
    ),
    "faults": (
        "Faults act in the events phase, after the scheduled events and the world's"
        " elements: random failure clocks, then hazard zones, then the out-of-contact rule"
        " (a working robot without a main-channel link for more than"
        " `fail_if_out_of_contact_for` steps fails). Batteries are paid after the"
        " communication phase; a robot whose battery is empty fails there and then. Nobody"
        " is told: teammates and the base see only silence (a teammate silent for"
        " `simulation.presume_lost_after` steps is presumed lost). What fails (`part`) is as"
        " in `fail` events; failures of one part add up (it works again once each is"
        " repaired). Details: docs/faults.md."
    ),
    "faults.random[i]": (
        "Exactly one law: `mtbf` (exponential times between failures), `shape` and `scale`"
        " (Weibull) or `probability` (per step: geometric). Common random numbers: each"
        " robot's times are drawn from the stream `fault/<i>` of the seed keyed by its name,"
        " so the strategy never changes when a robot fails. The first failure comes at"
        " `after` plus a drawn time; with `recover_after` the part works again that many steps"
        " later and the next time is drawn from then on, up to `max_failures`; without it the"
        " part is lost for good (one failure). No failure comes after `until`."
    ),
    "faults.battery": (
        "Each listed robot starts full; after each step's communication phase its charge"
        " drops by `per_cell` per cell moved, `per_scan` per scan and `per_message` per"
        " message (bytes sent to one agent in one step, on either channel). At 0 it fails."
        " Its level, a fraction of `capacity`, is part of its own knowledge (`RobotView."
        "battery`) and is drawn by its name in videos."
    ),
    "faults.hazards[i]": (
        "Each step a working robot starts with its centre in the zone counts as a step of"
        " exposure; it fails (its `part`) on the step that spends an exposure budget drawn"
        " once at the start from the stream `hazard/<i>` keyed by its name (geometric with"
        " `probability`: the law of a failure with that probability at each step inside). So"
        " a robot fails after the same number of steps inside whatever its strategy. One"
        " failure per zone and robot. A zone must cover a cell of the map; the `hazards`"
        " video layer tints it."
    ),
}


def type_name(annotation: Any) -> str:
    """A short readable name of a field's type."""
    members = get_args(annotation)
    if get_origin(annotation) in (Union, UnionType) and members:
        return " or ".join("None" if m is type(None) else type_name(m) for m in members)
    if get_origin(annotation) is Annotated:
        return type_name(members[0])
    if get_origin(annotation) is Literal:
        return " or ".join(repr(m) for m in members)
    text = getattr(annotation, "__name__", None) or str(annotation)
    text = text.replace("typing.", "").replace("mresim_phys.scenario.schema.", "")
    text = text.replace("mresim_phys.scenario.maps.", "")
    for module in ("shapes", "obstacles", "doors", "debris", "terrain"):
        text = text.replace(f"mresim_phys.world.{module}.", "")
    return text.replace(" | ", " or ")


def default_text(field: Any) -> str:
    """The default as YAML-ish text, or 'required'."""
    if field.default is PydanticUndefined and field.default_factory is None:
        return "**required**"
    value = field.default_factory() if field.default_factory is not None else field.default
    if isinstance(value, BaseModel):
        return "(defaults below)"
    return f"`{value!r}`"


def table(model: type[BaseModel], own_only: bool = False) -> list[str]:
    """Markdown rows for a model's fields."""
    rows = ["| key | type | default | allowed | meaning |", "|---|---|---|---|---|"]
    parents = [b for b in model.__mro__[1:] if isinstance(b, type) and issubclass(b, BaseModel)]
    inherited = set().union(*(b.model_fields for b in parents)) if own_only else set()
    for name, field in model.model_fields.items():
        if name in inherited:
            continue
        meaning = (field.description or "").replace("|", "/")
        allowed = bounds_text(name, field)
        cells = [f"`{name}`", type_name(field.annotation), default_text(field), allowed, meaning]
        rows.append("| " + " | ".join(cells) + " |")
    return rows


def render() -> str:
    """The whole reference page."""
    lines = [
        "# Scenario reference",
        "",
        "Generated by `python tools/make_scenario_reference.py` from the pydantic schema",
        "(`mresim_phys/scenario/schema.py`) and the plugin registries; do not edit by hand.",
        "Unknown keys are errors at every level. World units are cells; `map.resolution`",
        "(metres per cell) is only used to report metres. Relative paths resolve against",
        "the YAML file. `team` gives every robot's defaults; a robot may override any",
        "field, and a robot's `sensor` keys merge into the team's.",
        "",
        *numbers_paragraph(),
        "",
        *plugins_paragraph(),
        "",
    ]
    for title, model in SECTIONS:
        head = [f"## {title}", ""] if title else []
        note = [NOTES[title], ""] if title in NOTES else []
        lines += [*head, *note, *table(model, own_only=model is schema.RobotSpec), ""]
    lines += [
        "## events[i]",
        "",
        "Each entry is one event; the key that names its kind (below) marks which:",
        "`{step: 300, fail: B}` is a `fail` event. Events act in list order at the start",
        "of their step (step 0: before the first scans).",
        "",
        *plugin_tables(EVENTS),
    ]
    registries = (
        ("Strategies", STRATEGIES),
        ("Planners", PLANNERS),
        ("Communication models", COMM_MODELS),
    )
    for kind, registry in registries:
        lines += [f"## {kind}", "", *plugin_tables(registry)]
    return "\n".join(lines).rstrip() + "\n"


def numbers_paragraph() -> list[str]:
    """How numbers are checked, in every model and every plugin's params alike."""
    low, high = UNIT_BOUNDS["_dbm"]
    return [
        "Numbers are checked alike everywhere, plugin params included: every number is",
        "finite (`.inf` and `.nan` are errors), `true`/`false` is not a number, and the",
        "'allowed' column gives its bounds (x stands for the value, or each number of a",
        f"list or point). A field in dBm (`*_dbm`) lies within {low:g} .. {high:g}; any other",
        f"number without bounds of its own within +-{MAX_FLOAT:g} (floats) or +-{MAX_INT}",
        "(integers): a value beyond is taken for a mistake. Names (of the scenario and",
        "of robots) name output folders: letters, digits, `_`, `.` and `-`, not only dots.",
        "A key given twice in one mapping is an error, as is a snapshot step past `steps`.",
        "Every YAML file read (scenarios, studies, ROS map files) is refused unread when",
        f"it is over {MAX_YAML_BYTES // 2**20} MB or not a regular file, and before any value",
        f"is built when its aliases (`*name`) would add over {MAX_ALIAS_VALUES:,} values",
        "once expanded (an alias bomb) or an alias refers to a value holding it (a loop).",
    ]


def plugins_paragraph() -> list[str]:
    """What a ``package.module:Class`` reference does: it imports, so it runs, code."""
    bases = ", ".join(
        f"{r.kind}: `{r.family.params.__name__}`"
        for r in (STRATEGIES, PLANNERS, COMM_MODELS)
        if r.family is not None
    )
    return [
        "Plugins (`strategy`, `planner`, `communication.model`) are chosen by a registered",
        "name or by `package.module:ClassName`. **A `module:Class` reference imports that",
        "module, which runs its code** with your rights, in `mresim run` and `validate`, in",
        "every worker process of a sweep and on every Dask worker: a scenario or study file",
        "that names one is code, so run only such files from people you trust. The class",
        "must be of the field's family: its `Params` subclasses the family's params model",
        f"({bases})",
        "and it has the family's methods (docs/writing-a-strategy.md); a class of another",
        "family (a strategy given as a planner) is refused when the file is read.",
    ]


def plugin_tables(registry: Any) -> list[str]:
    """One section per registered plugin: its docstring's first line and its params."""
    lines: list[str] = []
    for name in registry.names():
        cls = registry.get(name)
        doc = (cls.__doc__ or "").strip().splitlines()[0]
        lines += [f"### `{name}`", "", doc, "", *table(cls.Params), ""]
    return lines


if __name__ == "__main__":
    out = ROOT / "docs" / "scenario-reference.md"
    out.write_text(render(), encoding="utf-8")
    print(f"wrote {out}")
