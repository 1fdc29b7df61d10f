"""Viewer (output edge), replay source: any step of a run log, fast, without re-simulating.

A run log stores each step as its changes since the step before (docs/run-log-format.md),
so step k is reached by replaying steps 0..k. :class:`LogIndex` does that once when the
viewer opens a log, recording the explored / known-at-base series, the events and, every
:data:`KEYFRAME_EVERY` steps, a *keyframe*: the replay's whole state (``Replay``: every
agent's grids and points, the truth, the coverage and failure counts), pickled and
compressed in memory. :meth:`ReplaySource.snapshot` then restores the nearest keyframe at
or before k and replays at most ``KEYFRAME_EVERY - 1`` steps (or steps on from where it
is), so any seek costs a bounded, small amount (measured in docs/viewer.md). Snapshots
equal those of a sequential replay field by field (tests/test_viewer_replay.py).

Typical use: ``source = ReplaySource.open(run_dir); snap = source.snapshot(1500)``.
"""

from __future__ import annotations

import json
import pickle
import threading
import zlib
from collections import OrderedDict
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mresim_phys.errors import MresimError
from mresim_phys.knowledge.activity import health_of
from mresim_phys.knowledge.latest import LatestCoverage
from mresim_phys.output.logformat import Chunk
from mresim_phys.output.logmeta import damaged
from mresim_phys.output.replay import render_spec, replay_regions, run_scenario
from mresim_phys.output.runlog import STEPS, Replay, RunLog
from mresim_phys.render import LayerSpec, parse_layers
from mresim_phys.snapshot import Snapshot
from mresim_phys.viewer.frames import FrameMaker
from mresim_phys.viewer.protocol import info_message
from mresim_phys.viewer.timeline import Timeline
from mresim_phys.world.explorable import Explorable

KEYFRAME_EVERY = 50  # logged steps between keyframes: a seek replays fewer than this
CHUNKS_KEPT = 3  # delta chunks kept decoded
DECODE_ERRORS = (AttributeError, KeyError, IndexError, TypeError, ValueError)


def freeze(replay: Replay) -> bytes:
    """The replay's state as compressed bytes (its log, cached views and explorable area
    left out: the area is a function of the truth, rebuilt by :func:`thaw`)."""
    left_out = ("log", "_maps", "explorable")
    state = {k: v for k, v in vars(replay).items() if k not in left_out}
    return zlib.compress(pickle.dumps(state, protocol=pickle.HIGHEST_PROTOCOL), 1)


def thaw(data: bytes, log: RunLog) -> Replay:
    """A replay in the state :func:`freeze` saved, reading ``log``.

    Pickling turns views into copies, so the views a replay shares are made again: the
    per-robot map views (rebuilt on demand) and a 'latest' coverage's view of the truth;
    the explorable area is computed afresh on the truth (the same cells it followed).
    """
    replay = Replay.__new__(Replay)
    vars(replay).update(pickle.loads(zlib.decompress(data)))  # our own bytes, never a file
    replay.log, replay._maps = log, {}
    truth = replay.truth.view(bool).reshape(replay.shape)
    if isinstance(replay.coverage, LatestCoverage):
        replay.coverage.truth = truth
    replay.explorable = Explorable(truth, replay.sights) if replay.sights else None
    if replay.explorable is not None:
        replay.coverage.reachable = replay.explorable.mask
    return replay


@dataclass
class LogIndex:
    """What one pass over a log learnt: keyframes, the steps' lines and the timeline."""

    lines: list[dict[str, Any]]
    keyframes: dict[int, bytes] = field(default_factory=dict)  # logged step n -> state before it
    timeline: Timeline = field(default_factory=Timeline)


class ReplaySource:
    """The snapshots of one logged run, by step, for the viewer (thread-safe)."""

    mode = "replay"

    def __init__(self, run_dir: Path, log: RunLog, every: int = KEYFRAME_EVERY) -> None:
        self.run_dir, self.log, self.every = run_dir, log, every
        self.names: list[str] = list(log.names)
        self.spec = render_spec(run_dir, {}, default_video=False)
        scenario = run_scenario(run_dir)
        self._regions: dict[int, Any] = {}
        self._scenario = scenario
        self.frames = FrameMaker(log.truth.shape, self.spec.scale, self._regions_for)
        self._chunks: OrderedDict[int, Chunk] = OrderedDict()
        self._lock = threading.RLock()
        self.index = self._build_index()
        self._replay: Replay | None = None
        self._next = 0  # logged step the current replay applies next
        self._snap: Snapshot | None = None

    @classmethod
    def open(cls, run_dir: Path, every: int = KEYFRAME_EVERY) -> ReplaySource:
        """Open ``run_dir``'s log and index it; MresimError if it has none or is damaged."""
        run_dir = Path(run_dir)
        if not run_dir.is_dir():
            raise MresimError(f"{run_dir}: no such run folder (give a folder `mresim run` wrote)")
        log = RunLog.open(run_dir / "log")
        if log.steps == 0:
            raise damaged(log.log_dir, "it holds no step")
        return cls(run_dir, log, every)

    @property
    def steps(self) -> int:
        """Number of logged steps (logged steps 0 .. steps - 1)."""
        return self.log.steps

    def _regions_for(self, snap: Snapshot) -> Any:
        """Region polygons through the truth of ``snap``'s world version (as replay does)."""
        version = snap.world_version
        if version not in self._regions:
            if len(self._regions) > 4:
                self._regions.clear()
            self._regions[version] = replay_regions(self._scenario, snap.truth, snap.movables)
        return self._regions[version]

    def _read_lines(self) -> list[dict[str, Any]]:
        path = self.log.log_dir / STEPS
        try:
            with path.open(encoding="utf-8") as handle:
                lines = [json.loads(handle.readline()) for _ in range(self.steps)]
        except (OSError, UnicodeDecodeError, ValueError) as exc:
            raise damaged(self.log.log_dir, f"{STEPS}: {exc}") from None
        if not all(isinstance(line, dict) for line in lines):
            raise damaged(self.log.log_dir, f"{STEPS}: a line is not a JSON object")
        return lines

    def _chunk(self, n: int) -> tuple[Chunk, int]:
        """The decoded chunk of logged step ``n`` and ``n``'s place in it."""
        per = int(self.log.meta["chunk_steps"])
        index = n // per
        chunk = self._chunks.pop(index, None)
        if chunk is None:
            chunk = self.log.read_chunk(index)
        self._chunks[index] = chunk
        while len(self._chunks) > CHUNKS_KEPT:
            self._chunks.popitem(last=False)
        return chunk, n % per

    def _apply(self, replay: Replay, lines: list[dict[str, Any]], n: int) -> Snapshot:
        """Apply logged step ``n`` to ``replay``; a damaged step is a user error."""
        chunk, j = self._chunk(n)
        try:
            snap, _ = replay.step(lines[n], chunk, j)
        except DECODE_ERRORS as exc:
            raise damaged(self.log.log_dir, f"logged step {n}: {exc!r}") from None
        return snap

    def _build_index(self) -> LogIndex:
        """One pass over the log: keyframes, metrics and events of every step."""
        index = LogIndex(self._read_lines())
        replay = Replay(self.log)
        for n in range(self.steps):
            if n % self.every == 0:
                index.keyframes[n] = freeze(replay)
            chunk, j = self._chunk(n)
            try:
                snap, record = replay.step(index.lines[n], chunk, j)
            except DECODE_ERRORS as exc:
                raise damaged(self.log.log_dir, f"logged step {n}: {exc!r}") from None
            robots = snap.robots
            states, reasons = [a.state for a in robots], [health_of(a).reason for a in robots]
            index.timeline.add(record, snap.events, states, reasons)
        return index

    def snapshot(self, n: int) -> Snapshot:
        """The snapshot of logged step ``n`` (clamped to the log); valid until the next call."""
        with self._lock:
            n = min(max(int(n), 0), self.steps - 1)
            if self._snap is not None and self._next - 1 == n:
                return self._snap
            start = n - n % self.every
            if self._replay is None or not start <= self._next <= n:
                self._replay, self._next = thaw(self.index.keyframes[start], self.log), start
            snap = None
            while self._next <= n:
                snap = self._apply(self._replay, self.index.lines, self._next)
                self._next += 1
            assert snap is not None
            self._snap = snap
            return snap

    def frame(self, n: int, layers: LayerSpec, known: int) -> tuple[dict[str, Any], bytes]:
        """The page's frame message for logged step ``n``: header and PNG."""
        with self._lock:
            snap = self.snapshot(n)
            png = self.frames.png(snap, layers)
            header = {
                "type": "frame",
                "n": min(max(n, 0), self.steps - 1),
                "step": snap.step,
                "agents": self.frames.agents(snap),
                "events": list(snap.events),
                "timeline": None,  # a replay sends the whole timeline in its info
                "playing": False,
                "finished": True,
            }
            return header, png

    def info(self) -> dict[str, Any]:
        """The page's info message: the run's agents, layers and whole timeline."""
        names = list(self.log.names)
        kinds = [str(a["kind"]) for a in self.log.meta["agents"]]
        try:
            layers = parse_layers(self.spec.layers)
        except ValueError:
            layers = LayerSpec()
        extra = {
            "steps": self.steps,
            "name": self.log.meta["name"],
            "seed": self.log.meta["seed"],
            "timeline": self.index.timeline.to_json(),
        }
        return info_message(self.mode, names, kinds, layers, self.frames.size, extra)

    def warm_up(self) -> None:
        """Render step 0 once, so the first seek does not pay for compiling the kernels."""
        self.frame(0, LayerSpec.all(), 0)
