"""Viewer (output edge), live source: a running simulation driven from the page.

:meth:`LiveSource.on_step` is the run session's per-step hook (``output.session``): it runs
in the simulation's thread after every step, so while it waits the simulation really is
paused, and while it renders the snapshot's live grids cannot change under it. It
records the step in the timeline, renders a frame for every page that asked for one
(pull: a page asks again once it has shown a frame, so a slow page never queues frames),
then, when paused, waits for play, a single step or stop, serving frames (a new layer set)
meanwhile. Stop asks the session to end after this step (:class:`ViewerStop`), which then
writes every output as for a run stopped by Ctrl-C. Nothing here changes the simulation:
a run with a page attached gives the same bytes as one without.

The run waits, paused at step 0, until the first page connects, then plays.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from mresim_phys.metrics import StepRecord
from mresim_phys.output.signals import StopRequest
from mresim_phys.render import LayerSpec, parse_layers
from mresim_phys.sim import Simulation
from mresim_phys.snapshot import Snapshot
from mresim_phys.viewer.frames import FrameMaker
from mresim_phys.viewer.protocol import info_message
from mresim_phys.viewer.timeline import Timeline

WAIT_S = 0.05  # how often a paused simulation looks for requests


class ViewerStop(StopRequest):
    """A stop request that the page can make too (reported as ``signal: viewer``)."""

    def __init__(self, notice: bool = True) -> None:
        super().__init__(notice)
        self.by_viewer = False

    @property
    def requested(self) -> bool:
        """A stop signal arrived or the page pressed stop."""
        return self.signum is not None or self.by_viewer

    @property
    def name(self) -> str | None:
        """The signal's name, ``viewer`` for the page's stop, or None."""
        return "viewer" if self.signum is None and self.by_viewer else super().name


Deliver = Callable[[dict[str, Any], bytes], None]


@dataclass
class Want:
    """A page's pending frame request: its layers and how to hand it the frame."""

    layers: LayerSpec
    deliver: Deliver
    known: int  # timeline entries the page already has


@dataclass
class Controls:
    """What the page asked of the simulation (guarded by ``LiveSource.cond``)."""

    playing: bool = False
    started: bool = False  # a page connected (the run waits for one)
    steps: int = 0  # single steps asked for while paused
    speed: float = 0.0  # steps per second while playing; 0: as fast as it goes
    wants: dict[int, Want] = field(default_factory=dict)  # page id -> its request


class LiveSource:
    """A running simulation seen and driven by pages."""

    mode = "live"

    def __init__(self, sim: Simulation, stop: ViewerStop, frames: FrameMaker) -> None:
        self.sim, self.stop, self.frames = sim, stop, frames
        self.cond = threading.Condition()
        self.controls = Controls()
        self.timeline = Timeline()
        self.step = 0
        self.finished = False
        self._last = 0.0  # perf_counter of the last step while playing
        first = sim.snapshot()
        self.names = [a.name for a in first.agents]
        self.kinds = [a.kind for a in first.agents]

    # -- called by the server (event loop thread) --------------------------------------------
    def connect(self) -> None:
        """A page connected: the first one starts the run."""
        with self.cond:
            if not self.controls.started:
                self.controls.started = self.controls.playing = True
            self.cond.notify_all()

    def request(self, page: int, want: Want) -> None:
        """Page ``page`` wants the newest frame (served after the next step, or now if paused)."""
        with self.cond:
            self.controls.wants[page] = want
            if self.finished:  # nothing steps any more: serve from here
                self._serve()
            self.cond.notify_all()

    def forget(self, page: int) -> None:
        """Page ``page`` went away."""
        with self.cond:
            self.controls.wants.pop(page, None)

    def command(self, op: str, value: float = 0.0) -> None:
        """play, pause, step (one step, paused), speed (steps per second) or stop."""
        with self.cond:
            c = self.controls
            if op == "play":
                c.playing = True
            elif op == "pause":
                c.playing = False
            elif op == "step":
                c.playing, c.steps = False, c.steps + 1
            elif op == "speed":
                c.speed = max(float(value), 0.0)
            elif op == "stop":
                self.stop.by_viewer, c.playing = True, False
            self.cond.notify_all()

    def status(self) -> dict[str, Any]:
        """Step, play state and whether the run ended."""
        with self.cond:
            playing = self.controls.playing and not self.finished
            return {"step": self.step, "playing": playing, "finished": self.finished}

    def info(self) -> dict[str, Any]:
        """The page's info message (the timeline comes with the frames)."""
        try:
            layers = parse_layers(self.sim.scenario.render.layers)
        except ValueError:
            layers = LayerSpec()
        extra = {
            "steps": self.sim.scenario.steps + 1,
            "name": self.sim.scenario.name,
            "seed": self.sim.scenario.seed,
            "timeline": Timeline().to_json(),
        }
        return info_message(self.mode, self.names, self.kinds, layers, self.frames.size, extra)

    # -- called by the simulation thread -----------------------------------------------------
    def on_step(self, record: StepRecord) -> None:
        """The session's hook: note the step, serve frames, hold while paused."""
        states = [r.state for r in record.robots]
        reasons = [self.sim.health.view(r.name)[1] for r in record.robots]
        with self.cond:
            self.timeline.add(record, self.sim.events_now, states, reasons)
            self.step = record.step
            self._pace()
            self._serve()
            while not self._may_go():
                self.cond.wait(WAIT_S)
                if not self._going():  # a frame now would show the step before the next
                    self._serve()

    def end(self) -> None:
        """The run ended: serve the last frame to waiting pages."""
        with self.cond:
            self.finished = True
            self._serve()

    def _may_go(self) -> bool:
        """Whether the simulation may take its next step (uses up a single step)."""
        c = self.controls
        if self.stop.requested or (c.playing and c.started):
            return True
        if c.steps > 0:
            c.steps -= 1
            return True
        return False

    def _going(self) -> bool:
        """Whether the simulation is about to step (played, stepped or stopped)."""
        c = self.controls
        return self.stop.requested or (c.playing and c.started) or c.steps > 0

    def _pace(self) -> None:
        """Hold the step rate to the page's speed: a new speed applies at once (a very
        slow one is not waited out), pause or stop ends the wait."""
        while self.controls.playing and not self.stop.requested and self.controls.speed > 0:
            left = self._last + 1.0 / self.controls.speed - time.perf_counter()
            if left <= 0:
                break
            self.cond.wait(min(left, WAIT_S))
        self._last = time.perf_counter()

    def _serve(self) -> None:
        """Render the current snapshot for every page waiting for a frame."""
        wants, self.controls.wants = self.controls.wants, {}
        if not wants:
            return
        snap: Snapshot = self.sim.snapshot()
        agents = self.frames.agents(snap)
        for want in wants.values():
            header = {
                "type": "frame",
                "n": len(self.timeline) - 1,
                "step": snap.step,
                "agents": agents,
                "events": list(snap.events),
                "timeline": self.timeline.to_json(want.known),
                **self._flags(),
            }
            want.deliver(header, self.frames.png(snap, want.layers))

    def _flags(self) -> dict[str, Any]:
        c = self.controls
        return {"playing": c.playing and not self.finished, "finished": self.finished}
