"""Run sessions (output edge): one loop over the steps, feeding every recorder.

:func:`run_session` is the only loop of a command-line run: it takes each step's
record from ``Simulation.iterate()`` and hands it, with a lazily built snapshot,
to each :class:`Recorder` (metrics files, run log, video, PNG snapshots). Rendering
never happens inside ``Simulation.step()``. An interrupted run still closes
every recorder, so nothing already written is lost.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

from mresim_phys.comms.regions import RegionProbe
from mresim_phys.errors import ScenarioError
from mresim_phys.metrics import StepRecord
from mresim_phys.output.recorders import RunWriter, summarise
from mresim_phys.output.runlog import RunLogWriter
from mresim_phys.output.video import VideoRecorder, default_video_path, write_png
from mresim_phys.render.frame import Renderer, parse_layers
from mresim_phys.scenario.schema import RenderSpec
from mresim_phys.sim import Simulation
from mresim_phys.snapshot import Snapshot

SnapshotSource = Callable[[], Snapshot]


class Recorder(Protocol):
    """Something that consumes every step of a run."""

    def on_step(self, record: StepRecord, snapshot: SnapshotSource) -> None:
        """Consume one step (``snapshot()`` builds the step's snapshot on demand)."""
        ...

    def close(self) -> None:
        """Flush and release files."""
        ...


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


class LogRecorder:
    """The run log (poses, states, links, events, map deltas) for replay."""

    def __init__(self, log_dir: Path, name: str, seed: int) -> None:
        self.log_dir, self.name, self.seed = log_dir, name, seed
        self.writer: RunLogWriter | None = None

    def on_step(self, record: StepRecord, snapshot: SnapshotSource) -> None:
        """Log the step (the first call writes the static data and step 0)."""
        if self.writer is None:
            self.writer = RunLogWriter(self.log_dir, snapshot(), name=self.name, seed=self.seed)
        else:
            self.writer.write(snapshot())

    def close(self) -> None:
        """Flush the last chunk."""
        if self.writer is not None:
            self.writer.close()


class FrameRecorder:
    """Video frames every ``every`` steps, PNGs at chosen steps and of the last step."""

    def __init__(
        self,
        renderer: Renderer,
        video: VideoRecorder | None,
        every: int,
        png_steps: Sequence[int],
        png_dir: Path,
        final_png: bool,
    ) -> None:
        self.renderer, self.video, self.every = renderer, video, every
        self.png_steps, self.png_dir, self.final_png = set(png_steps), png_dir, final_png
        self.last: Snapshot | None = None

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
            write_png(self.png_dir / f"step-{record.step:05d}.png", frame)

    def close(self) -> None:
        """Close the video and write the final picture."""
        if self.video is not None:
            self.video.close()
        if self.final_png and self.last is not None:
            write_png(self.png_dir / "final.png", self.renderer.render(self.last))


def once(build: SnapshotSource) -> SnapshotSource:
    """``build`` called at most once; later calls return the same snapshot."""
    cache: list[Snapshot] = []

    def get() -> Snapshot:
        if not cache:
            cache.append(build())
        return cache[0]

    return get


@dataclass
class Outcome:
    """What a session produced."""

    summary: dict[str, object]
    out_dir: Path
    video: Path | None
    reason: str


def video_path(spec: RenderSpec, name: str, seed: int) -> Path | None:
    """Where the video goes, or None for no video."""
    if spec.video is False:
        return None
    return default_video_path(name, seed) if spec.video is True else Path(str(spec.video))


def frame_recorder(sim: Simulation, spec: RenderSpec, out_dir: Path) -> FrameRecorder | None:
    """The renderer-backed recorder the render spec asks for, if any."""
    path = video_path(spec, sim.scenario.name, sim.scenario.seed)
    if path is None and not spec.snapshots and not spec.final_png:
        return None
    try:
        layers = parse_layers(spec.layers)
        layers.check_agents([r.name for r in sim.robots])
    except ValueError as exc:
        raise ScenarioError(f"render.layers: {exc}") from None
    regions = RegionProbe.of(sim.scenario, sim.world)
    renderer = Renderer(sim.parts.truth.occupied.shape, layers, spec.scale, regions=regions)
    video = None
    if path is not None:
        video = VideoRecorder(path, spec.fps, renderer.size)
    return FrameRecorder(renderer, video, spec.every, spec.snapshots, out_dir, spec.final_png)


def make_recorders(sim: Simulation, out_dir: Path) -> tuple[RunWriter, list[Recorder], Path | None]:
    """Metrics writer, every recorder the scenario's render block asks for, the video path."""
    spec, scenario = sim.scenario.render, sim.scenario
    frames = frame_recorder(sim, spec, out_dir)  # first: it checks the layers
    try:
        writer = RunWriter(out_dir, scenario)
    except OSError:
        if frames is not None:
            frames.close()
        raise
    recorders: list[Recorder] = [MetricsRecorder(writer)]
    if spec.log:
        recorders.append(LogRecorder(out_dir / "log", scenario.name, scenario.seed))
    if frames is not None:
        recorders.append(frames)
    return writer, recorders, video_path(spec, scenario.name, scenario.seed)


def run_session(
    sim: Simulation, out_dir: Path, on_step: Callable[[StepRecord], None] | None = None
) -> Outcome:
    """Run ``sim`` to its end, feeding every recorder; write summary.json (and plots)."""
    writer, recorders, video = make_recorders(sim, out_dir)
    started, reason = time.perf_counter(), "interrupted"
    try:
        for record in sim.iterate():
            snapshot = once(sim.snapshot)
            for recorder in recorders:
                recorder.on_step(record, snapshot)
            if on_step is not None:
                on_step(record)
        reason = sim.stop_reason() or "steps"
    except KeyboardInterrupt:
        pass
    finally:
        for recorder in recorders:
            recorder.close()
    elapsed = time.perf_counter() - started
    summary = summarise(sim.scenario, sim.record, sim.milestones, elapsed, reason, sim.comm_totals)
    writer.write_summary(summary)
    return Outcome(summary, out_dir, video, reason)
