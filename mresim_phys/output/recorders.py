"""Recorders (output edge): everything that consumes a run's steps and what it leaves on disk.

A :class:`Recorder` sees every step: its metrics record and, built on demand, its
snapshot. :class:`MetricsRecorder` streams ``metrics.csv`` (through :class:`RunWriter`,
which also writes ``scenario.yaml``, the fully resolved scenario, and ``summary.json`` at
the end); :class:`LogRecorder` the run log (``output.runlog``); :class:`FrameRecorder`
video frames and PNGs, for live runs (``output.session``) and replays
(``output.replay``) alike. ``metrics.csv`` holds no wall-clock values, so the same
scenario and seed give a byte-identical file.
"""

from __future__ import annotations

import csv
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
import yaml

from mresim_phys.build import region_probe, run_rules
from mresim_phys.columns import (
    BEAM_COLUMN,
    CLOCK_COLUMN,
    LOCALIZATION_COLUMNS,
    MEETING_COLUMNS,
    TEAM_COLUMNS,
    Layout,
)
from mresim_phys.comms.radio_feature import radio_columns
from mresim_phys.comms.regions import RegionProbe
from mresim_phys.errors import ScenarioError
from mresim_phys.meetings.watch import strategies_plan_meetings
from mresim_phys.metrics import StepRecord
from mresim_phys.output.files import PendingFile, write_json_atomic, write_text_atomic
from mresim_phys.output.localization import PoseRecorder
from mresim_phys.output.logwriter import RunLogWriter
from mresim_phys.output.video import (
    CODECS,
    VideoRecorder,
    chosen_video_path,
    default_video_path,
    write_png,
)
from mresim_phys.render import LayerSpec, Renderer, frame_scale, parse_layers
from mresim_phys.scenario.faults import has_localization
from mresim_phys.scenario.run_specs import RenderSpec
from mresim_phys.scenario.schema import Scenario
from mresim_phys.snapshot import Snapshot
from mresim_phys.tracking import CommTotals, Milestones

if TYPE_CHECKING:
    from mresim_phys.sim import Simulation

SnapshotSource = Callable[[], Snapshot]


class Recorder(Protocol):
    """Something that consumes every step of a run."""

    def on_step(self, record: StepRecord, snapshot: SnapshotSource) -> None:
        """Consume one step (``snapshot()`` builds the step's snapshot on demand)."""
        ...

    def close(self) -> None:
        """Flush and release files."""
        ...

    def discard(self) -> None:
        """The run failed: release files, keeping nothing unfinished under a final name."""
        ...


def default_run_dir(scenario: Scenario) -> Path:
    """``runs/<name>/seed-<seed>`` under the current folder."""
    return Path("runs") / scenario.name / f"seed-{scenario.seed}"


def scenario_yaml(scenario: Scenario) -> str:
    """The resolved scenario as YAML (keys in schema order)."""
    return yaml.safe_dump(scenario.model_dump(mode="json"), sort_keys=False)


def run_layout(scenario: Scenario) -> Layout:
    """The columns of the run's ``metrics.csv`` (a world that changes: ``stale``; paired
    faults: the robustness columns; the optional columns its scenario names)."""
    rules = run_rules(scenario)
    names = [r.name for r in scenario.robots]
    extra = extra_columns(scenario)
    return Layout.of(names, latest=rules.latest, faults=rules.fault_columns, extra=extra)


def extra_columns(scenario: Scenario) -> list[str]:
    """The optional columns of the run: those its scenario names, then the localisation
    columns (``localization/feature.py``) if a robot has localisation, then the meeting
    columns (``meeting_board.py``) if a robot's strategy plans meetings, then the radio
    columns (``comms/radio_feature.py``), then ``noisy_readings`` if a robot's laser has a
    beam model (``readings_feature.py``), then ``decisions`` if a robot has a clock
    (``clocks/feature.py``), then the team columns with ``metrics.team``
    (``discovery_feature.py``), each unless named already."""
    named = list(scenario.metrics.columns)
    if has_localization(scenario):
        named += [c for c in LOCALIZATION_COLUMNS if c not in named]
    if plans_meetings(scenario):
        named += [c for c in MEETING_COLUMNS if c not in named]
    named += [c for c in radio_columns(scenario.communication) if c not in named]
    if any(r.sensor.beam is not None for r in scenario.robots) and BEAM_COLUMN not in named:
        named.append(BEAM_COLUMN)
    if any(r.clock is not None for r in scenario.robots) and CLOCK_COLUMN not in named:
        named.append(CLOCK_COLUMN)
    if scenario.metrics.team:
        team = (*TEAM_COLUMNS, "longest_path", "connected_to_base")
        named += [c for c in team if c not in named]
    return named


def plans_meetings(scenario: Scenario) -> bool:
    """Whether a robot of ``scenario`` runs a strategy that plans meetings."""
    return strategies_plan_meetings(r.strategy.name for r in scenario.robots)


class RunWriter:
    """Streams ``metrics.csv`` during a run and writes ``summary.json`` when closed.

    Every file appears whole or not at all (``output.files``): ``scenario.yaml`` and
    ``summary.json`` through a temporary sibling, ``metrics.csv`` under a temporary name
    renamed at :meth:`close` (a row that cannot be written raises WriteError and deletes
    it).
    """

    def __init__(self, out_dir: Path, scenario: Scenario) -> None:
        self.out_dir = out_dir
        out_dir.mkdir(parents=True, exist_ok=True)
        write_text_atomic(out_dir / "scenario.yaml", scenario_yaml(scenario))
        self.path = out_dir / "metrics.csv"
        self._file = PendingFile(self.path)
        self._csv = csv.writer(self._file, lineterminator="\n")
        self.layout = run_layout(scenario)
        self._csv.writerow(self.layout.header())

    def on_step(self, record: StepRecord) -> None:
        """Append one row."""
        self._csv.writerow(self.layout.row(record))

    def close(self) -> None:
        """Close ``metrics.csv`` and give it its name (idempotent; WriteError if a row
        could not be written)."""
        self._file.commit()

    def discard(self) -> None:
        """Close and delete the unfinished ``metrics.csv``."""
        self._file.discard()

    def write_summary(self, summary: dict[str, Any]) -> Path:
        """Write ``summary.json`` and return its path."""
        return write_json_atomic(self.out_dir / "summary.json", summary)


def summarise(
    scenario: Scenario,
    last: StepRecord,
    milestones: Milestones,
    wall_time_s: float,
    stop_reason: str,
    comm: CommTotals | None = None,
) -> dict[str, Any]:
    """The run's headline numbers for ``summary.json``."""
    return {
        "name": scenario.name,
        "seed": scenario.seed,
        "steps": last.step,
        "stop_reason": stop_reason,
        "wall_time_s": round(wall_time_s, 3),
        "steps_per_second": round(last.step / wall_time_s, 2) if wall_time_s > 0 else None,
        "final_explored": last.explored,
        "final_known_at_base": last.known_at_base,
        "steps_to_explored": milestones.explored,
        "steps_to_known_at_base": milestones.known_at_base,
        "total_distance": last.distance,
        "alive": last.alive,
        "robots": {
            r.name: {"distance": r.distance, "state": r.state, "base_contact": r.base_contact}
            for r in last.robots
        },
        "communication": (comm or CommTotals()).summary(),
    }


class MetricsRecorder:
    """metrics.csv as the run goes (wraps :class:`RunWriter`)."""

    def __init__(self, writer: RunWriter) -> None:
        self.writer = writer

    def on_step(self, record: StepRecord, snapshot: SnapshotSource) -> None:
        """Append the step's row."""
        self.writer.on_step(record)

    def close(self) -> None:
        """Close metrics.csv."""
        self.writer.close()

    def discard(self) -> None:
        """Delete the unfinished metrics.csv."""
        self.writer.discard()


class LogRecorder:
    """The run log (every snapshot field, as map deltas and JSON lines) for replay."""

    def __init__(
        self, log_dir: Path, name: str, seed: int, faults: bool = False, columns: Sequence[str] = ()
    ) -> None:
        self.log_dir, self.name, self.seed, self.faults = log_dir, name, seed, faults
        self.columns = tuple(columns)
        self.writer: RunLogWriter | None = None

    def on_step(self, record: StepRecord, snapshot: SnapshotSource) -> None:
        """Log the step (the first call writes the static data and step 0)."""
        if self.writer is None:
            self.writer = RunLogWriter(
                self.log_dir,
                snapshot(),
                name=self.name,
                seed=self.seed,
                faults=self.faults,
                columns=self.columns,
            )
        else:
            self.writer.write(snapshot())

    def close(self) -> None:
        """Flush the last chunk."""
        if self.writer is not None:
            self.writer.close()

    def discard(self) -> None:
        """Release the log's files; it keeps ``closed: false`` and the chunks it committed."""
        if self.writer is not None:
            self.writer.abandon()


class FrameRecorder:
    """Video frames every ``every`` steps, PNGs at chosen steps and of the last step.

    PNGs are ``<png_dir>/<png_prefix>step-<step:05d>.png`` (and ``final.png``);
    ``pictures`` lists those written so far.
    """

    def __init__(
        self,
        renderer: Renderer,
        video: VideoRecorder | None,
        every: int,
        png_steps: Sequence[int],
        png_dir: Path,
        final_png: bool,
        png_prefix: str = "",
    ) -> None:
        self.renderer, self.video, self.every = renderer, video, every
        self.png_steps, self.png_dir, self.final_png = set(png_steps), png_dir, final_png
        self.png_prefix = png_prefix
        self.last: Snapshot | None = None
        self.pictures: list[Path] = []

    def on_step(self, record: StepRecord, snapshot: SnapshotSource) -> None:
        """Render when a frame or a PNG is due."""
        video_due = self.video is not None and record.step % self.every == 0
        png_due = record.step in self.png_steps
        if self.final_png:
            self.last = snapshot()
        if not (video_due or png_due):
            return
        frame = self.renderer.render(snapshot())
        if video_due and self.video is not None:
            self.video.write(frame)
        if png_due:
            self._png(f"{self.png_prefix}step-{record.step:05d}.png", frame)

    def close(self) -> None:
        """Close the video and write the final picture."""
        if self.video is not None:
            self.video.close()
        if self.final_png and self.last is not None:
            self._png("final.png", self.renderer.render(self.last))

    def discard(self) -> None:
        """Delete the unfinished video; write no final picture."""
        if self.video is not None:
            self.video.discard()

    def _png(self, name: str, frame: np.ndarray) -> None:
        path = self.png_dir / name
        write_png(path, frame)
        self.pictures.append(path)


def given(snapshot: Snapshot) -> SnapshotSource:
    """A snapshot source that gives ``snapshot`` (one already built, as in a replay)."""
    return lambda: snapshot


def checked_layers(text: str, names: Sequence[str]) -> LayerSpec:
    """``text`` parsed as layers whose per-robot overrides name agents in ``names``.

    Raises:
        ValueError: On an unknown layer, a malformed token or an unknown robot.
    """
    layers = parse_layers(text)
    layers.check_agents(names)
    return layers


def frame_recorder(
    spec: RenderSpec,
    layers: LayerSpec,
    shape: tuple[int, int],
    regions: RegionProbe | None,
    video: Path | None,
    png_dir: Path,
    *,
    final_png: bool,
    png_prefix: str = "",
) -> FrameRecorder:
    """A FrameRecorder of maps of ``shape`` with ``spec``'s scale, fps, every and PNG steps."""
    scale = frame_scale(shape, spec.scale, spec.min_side)
    renderer = Renderer(shape, layers, scale, regions=regions)
    fourcc = None if spec.codec is None else CODECS[spec.codec]
    writer = None if video is None else VideoRecorder(video, spec.fps, renderer.size, fourcc)
    steps = spec.snapshots
    return FrameRecorder(renderer, writer, spec.every, steps, png_dir, final_png, png_prefix)


def video_path(spec: RenderSpec, name: str, seed: int) -> Path | None:
    """Where a run's video goes, or None for no video."""
    if spec.video is False:
        return None
    return default_video_path(name, seed) if spec.video is True else chosen_video_path(spec.video)


def run_frames(sim: Simulation, out_dir: Path) -> FrameRecorder | None:
    """The FrameRecorder a live run's render block asks for, if any."""
    spec = sim.scenario.render
    path = video_path(spec, sim.scenario.name, sim.scenario.seed)
    if path is None and not spec.snapshots and not spec.final_png:
        return None
    try:
        layers = checked_layers(spec.layers, [r.name for r in sim.robots])
    except ValueError as exc:
        raise ScenarioError(f"render.layers: {exc}") from None
    regions = region_probe(sim.scenario, sim.world)
    shape = sim.world.shape
    return frame_recorder(spec, layers, shape, regions, path, out_dir, final_png=spec.final_png)


def make_recorders(sim: Simulation, out_dir: Path) -> tuple[RunWriter, list[Recorder], Path | None]:
    """Metrics writer, every recorder the scenario's render block asks for, the video path."""
    spec, scenario = sim.scenario.render, sim.scenario
    frames = run_frames(sim, out_dir)  # first: it checks the layers
    try:
        writer = RunWriter(out_dir, scenario)
    except BaseException:
        if frames is not None:
            frames.discard()
        raise
    recorders: list[Recorder] = [MetricsRecorder(writer)]
    if spec.log:
        columns = extra_columns(scenario)
        log = LogRecorder(out_dir / "log", scenario.name, scenario.seed, sim.fault_columns, columns)
        recorders.append(log)
    if frames is not None:
        recorders.append(frames)
    if has_localization(scenario):
        recorders.append(PoseRecorder())
    return writer, recorders, video_path(spec, scenario.name, scenario.seed)
