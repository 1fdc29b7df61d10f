"""Replay (output edge): re-render a run and recompute its metrics from its run log.

``mresim replay RUN_DIR`` reads ``RUN_DIR/log`` (see docs/run-log-format.md) and
``RUN_DIR/scenario.yaml`` (for the run's render settings), rebuilds every step's
snapshot from the log (``output.runlog.Replay``), and renders frames with any layers
through the live runs' ``FrameRecorder``, without re-simulating: frame for frame what
live rendering of that run gives.
With ``--metrics`` it recomputes ``metrics.csv`` from the log into
``metrics-replayed.csv`` and compares the two, and recomputes summary.json's run-health
record (``output.health``) and compares it too.
"""

from __future__ import annotations

import csv
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from mresim_phys.build import region_probe
from mresim_phys.columns import Layout
from mresim_phys.comms.regions import RegionProbe
from mresim_phys.errors import MresimError, ScenarioError
from mresim_phys.output.files import atomic_path
from mresim_phys.output.health import compare_health, compare_object
from mresim_phys.output.localization import PoseRecorder, replayed_localization
from mresim_phys.output.readings import replayed_readings
from mresim_phys.output.recorders import checked_layers, frame_recorder, given
from mresim_phys.output.runlog import Replay, RunLog
from mresim_phys.output.team import replayed_team
from mresim_phys.output.video import chosen_video_path
from mresim_phys.scenario.load import validate_scenario
from mresim_phys.scenario.readers import read_yaml_mapping
from mresim_phys.scenario.run_specs import RenderSpec
from mresim_phys.scenario.schema import Scenario
from mresim_phys.snapshot import MovableSnapshot
from mresim_phys.types import BoolGrid
from mresim_phys.world.space import World


@dataclass
class ReplayResult:
    """What a replay wrote and whether the recomputed metrics matched."""

    lines: list[str] = field(default_factory=list)
    ok: bool = True


def render_spec(run_dir: Path, overrides: dict[str, Any], default_video: bool) -> RenderSpec:
    """The run's render block with command-line overrides.

    Without ``--video`` or ``--snapshot`` a replay writes a video, unless it was
    asked only for ``--metrics``.
    """
    resolved = run_dir / "scenario.yaml"
    logged = read_yaml_mapping(resolved).get("render", {}) if resolved.is_file() else {}
    if not isinstance(logged, dict):
        raise MresimError(
            f"{resolved}: 'render' is {logged!r}, not a mapping; the run folder is damaged."
            " Fix or remove its scenario.yaml (replay then uses the default render settings)."
        )
    wants_frames = "video" in overrides or "snapshots" in overrides
    merged = {**logged, "snapshots": [], "video": default_video and not wants_frames}
    merged.update(overrides)
    try:
        return RenderSpec.model_validate(merged)
    except ValueError as exc:
        raise MresimError(f"replay of {run_dir}: bad render settings: {exc}") from None


def replay_video_path(spec: RenderSpec, log: RunLog) -> Path | None:
    """Where the replay's video goes (``videos/<name>-seed<seed>-replay.mp4`` by default)."""
    if spec.video is False:
        return None
    if spec.video is True:
        return Path("videos") / f"{log.meta['name']}-seed{log.meta['seed']}-replay.mp4"
    return chosen_video_path(spec.video)


def run_scenario(run_dir: Path) -> Scenario | None:
    """The run's resolved scenario, or None if it is missing or of another version."""
    resolved = run_dir / "scenario.yaml"
    if not resolved.is_file():
        return None
    try:
        return validate_scenario(read_yaml_mapping(resolved), str(resolved))
    except ScenarioError:
        return None  # a run of another version: draw range circles


def replay_regions(
    scenario: Scenario | None, truth: BoolGrid, movables: Sequence[MovableSnapshot] = ()
) -> RegionProbe | None:
    """The run's communication regions through the walls of ``truth`` (copied), past the
    obstacles among ``movables`` that the scenario says radio passes through."""
    return (
        None if scenario is None else region_probe(scenario, radio_world(scenario, truth, movables))
    )


def radio_world(scenario: Scenario, truth: BoolGrid, movables: Sequence[MovableSnapshot]) -> World:
    """A World of truth ``truth`` whose radio passes through the scenario's obstacles with
    ``blocks_radio: false`` that are on the map, as the live world's does."""
    quiet = {o.name for o in scenario.obstacles if not o.blocks_radio}
    placed = [m for m in movables if m.kind == "obstacle" and m.on and m.name in quiet]
    static = np.array(truth, dtype=bool)
    for m in placed:
        (row, col), (h, w) = m.at, m.cells.shape
        static[row : row + h, col : col + w] &= ~m.cells
    world = World(static, [])
    for m in placed:
        world.add_movable(m.name, m.cells, m.at, blocks_radio=False)
    return world


def replay_frames(
    log: RunLog, spec: RenderSpec, png_dir: Path, scenario: Scenario | None = None
) -> list[str]:
    """Render the logged run into a video and/or PNGs through a FrameRecorder, as live;
    return what was written. Region polygons follow the truth (and the obstacles radio
    passes through) when the world changes."""
    try:
        layers = checked_layers(spec.layers, log.names)
    except ValueError as exc:
        raise MresimError(f"--layers: {exc}") from None
    path = replay_video_path(spec, log)
    regions = replay_regions(scenario, log.truth)
    frames = frame_recorder(
        spec, layers, log.truth.shape, regions, path, png_dir, final_png=False, png_prefix="replay-"
    )
    version = None
    try:
        for snap, record in Replay(log).run():
            polygons = frames.renderer.regions is not None and not frames.renderer.regions.circles
            if polygons and snap.world_version != version:  # step 0, or the walls moved
                frames.renderer.regions = replay_regions(scenario, snap.truth, snap.movables)
            version = snap.world_version
            frames.on_step(record, given(snap))
    finally:
        frames.close()
    written = [f"picture {png}" for png in frames.pictures]
    if frames.video is not None:
        written.append(f"video {path} ({frames.video.frames_written} frames)")
    return written


def log_layout(log: RunLog, latest: bool) -> Layout:
    """The columns of the logged run's ``metrics.csv``, as its meta.json tells them."""
    return Layout.of(
        log.names[1:],
        latest=latest,
        faults=bool(log.meta.get("fault_columns", False)),
        connected=bool(log.meta.get("sights")),  # logs before the explorable area: no
        extra=[str(name) for name in log.meta.get("columns", [])],
    )


def replay_metrics(log: RunLog, run_dir: Path) -> tuple[list[str], bool]:
    """Write metrics-replayed.csv from the log and compare it with metrics.csv; recompute
    the run-health record and, for a run with localisation, the ``localization`` object (with
    a beam-model laser, the ``readings`` object), and compare them with summary.json's (one
    pass over the log)."""
    out = run_dir / "metrics-replayed.csv"
    latest = log.meta.get("beliefs") == "latest"
    replay, last, poses = Replay(log, latest), None, PoseRecorder()
    with atomic_path(out) as tmp, tmp.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle, lineterminator="\n")
        layout = log_layout(log, latest)
        writer.writerow(layout.header())
        for snap, record in replay.run():
            writer.writerow(layout.row(record))
            poses.note(record)
            last = snap
    health = replay.health_report(last).summary() if last is not None else {}
    lines, same_health = compare_health(health, run_dir)
    if last is not None and replay.coverage.connected is not None:
        reachable = replay.coverage.connected
        objects = replayed_localization(last, reachable, poses) | replayed_readings(last, reachable)
        objects |= replayed_team(last)
        for key, value in objects.items():
            more, same = compare_object(key, value, run_dir, key)
            lines, same_health = [*lines, *more], same_health and same
    live = run_dir / "metrics.csv"
    if not live.is_file():
        return [f"metrics recomputed into {out} (no metrics.csv to compare)", *lines], same_health
    same = live.read_bytes() == out.read_bytes()
    verdict = "identical to" if same else "DIFFERENT from"
    return [f"metrics recomputed into {out}: {verdict} {live}", *lines], same and same_health


def replay_run(run_dir: Path, overrides: dict[str, Any], metrics: bool) -> ReplayResult:
    """Replay the run in ``run_dir`` with the given render overrides."""
    log = RunLog.open(run_dir / "log")
    result = ReplayResult()
    spec = render_spec(run_dir, overrides, default_video=not metrics)
    if spec.video is not False or spec.snapshots:
        result.lines += replay_frames(log, spec, run_dir, run_scenario(run_dir))
    if metrics:
        lines, result.ok = replay_metrics(log, run_dir)
        result.lines += lines
    return result
