"""Run logs (output edge): write every snapshot of a run, replay it without re-simulating.

:class:`RunLogWriter` streams every step's :class:`~mresim_phys.snapshot.Snapshot` into a
``log/`` folder, every field of it as :mod:`~mresim_phys.output.logformat` says: one JSON
line per step (``steps.jsonl``: poses, states, goals, distances, links, events, the
world's version); grids (beliefs, safe space, skeletons, and the truth when the world
changed) as deltas since the previous logged step and paths and rendezvous points in
compressed chunks of ``chunk_steps`` steps (``deltas-NNNNN.npz``); static data
(``meta.json``, read back and checked by ``output.logmeta``; ``truth.npz``) once.
:class:`RunLog` opens a log; :class:`Replay` rebuilds
every snapshot in order, equal to the live one field by field, with each step's metrics
recomputed by the live code (``metrics.measure_step``); :func:`recompute_metrics` gives
the rows of ``metrics.csv`` from the log alone. Layout: ``docs/run-log-format.md``.
"""

from __future__ import annotations

import json
import zipfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from mresim_phys.errors import MresimError
from mresim_phys.knowledge.coverage import Coverage
from mresim_phys.knowledge.latest import LatestCoverage
from mresim_phys.knowledge.robustness import FailureWatch, robot_states
from mresim_phys.metrics import RobotRecord, StepRecord, measure_step, update_known_at_base
from mresim_phys.output.files import write_json_atomic
from mresim_phys.output.logformat import (
    AGENT_LINE,
    FORMAT,
    SNAPSHOT_LINE,
    STATIC_AGENT,
    TRUTH,
    VERSION,
    WORLD_GRIDS,
    Chunk,
    Track,
    chunk_arrays,
    decode_line,
    encode_line,
    new_parts,
    point,
)
from mresim_phys.output.logmeta import META, damaged, read_meta
from mresim_phys.output.logworld import MovablesTrack, movable_meta
from mresim_phys.snapshot import AgentSnapshot, CommSummary, Snapshot, read_only
from mresim_phys.types import FREE, BeliefGrid, BoolGrid, IntArray
from mresim_phys.world.maps import connected_to, free_components_mask, seed_cells
from mresim_phys.world.terrain import TerrainGrid

TRUTH_FILE, STEPS = "truth.npz", "steps.jsonl"


def chunk_file(index: int) -> str:
    """File name of delta chunk ``index`` (logged steps index*K .. index*K + K-1)."""
    return f"deltas-{index:05d}.npz"


def new_meta(
    first: Snapshot, name: str, seed: int, chunk_steps: int, faults: bool = False
) -> dict[str, Any]:
    """meta.json of a log about to get its first step (``fault_columns``: the run had
    faults, so its metrics.csv has the robustness columns; only written when true)."""
    meta: dict[str, Any] = {
        "format": FORMAT,
        "version": VERSION,
        "name": name,
        "seed": seed,
        "shape": list(first.truth.shape),
        "resolution": first.resolution,
        "chunk_steps": chunk_steps,
        "agents": [encode_line(STATIC_AGENT, a) for a in first.agents],
        "starts": [point(a.position) for a in first.robots],
        "movables": [movable_meta(m) for m in first.movables],
        "beliefs": "latest" if first.latest else "grow",
        "steps": 0,
        "closed": False,
    }
    if faults:
        meta["fault_columns"] = True
    return meta


def flat_cells(grid: np.ndarray) -> np.ndarray:
    """A flat uint8 copy of a bool or uint8 grid."""
    cells: np.ndarray = np.ascontiguousarray(grid).reshape(-1).view(np.uint8).copy()
    return cells


class RunLogWriter:
    """Streams a run's snapshots into ``log_dir``; ``first`` (step 0) is logged at once."""

    def __init__(
        self,
        log_dir: Path,
        first: Snapshot,
        *,
        name: str,
        seed: int,
        chunk_steps: int = 100,
        faults: bool = False,
    ) -> None:
        if chunk_steps < 1:
            raise ValueError(f"chunk_steps must be at least 1, not {chunk_steps}")
        cells = first.truth.size
        if cells >= 2**31:
            raise ValueError(f"a {first.truth.shape} grid is too large for int32 cell indices")
        self.log_dir, self.chunk_steps = Path(log_dir), chunk_steps
        self.log_dir.mkdir(parents=True, exist_ok=True)
        for stale in self.log_dir.glob("deltas-*.npz"):
            stale.unlink()
        self.meta = new_meta(first, name, seed, chunk_steps, faults)
        truth = np.packbits(first.truth, axis=None)
        statics: dict[str, Any] = {"occupied": truth}
        if first.terrain is not None:
            statics["terrain"] = first.terrain
        if first.prior is not None:
            statics["prior"] = first.prior
        if first.hazards is not None:
            statics["hazards"] = first.hazards
        np.savez_compressed(self.log_dir / TRUTH_FILE, **statics)
        self._tracks = [Track(cells) for _ in first.agents]
        self._truth = flat_cells(np.asarray(first.truth, dtype=bool))
        self._world = {g.name: np.zeros(cells, np.uint8) for g in WORLD_GRIDS}
        self._movables = MovablesTrack(first.movables)
        self._version = first.world_version
        self._lines: list[str] = []
        self._parts = new_parts()
        self._last_step: int | None = None
        self._steps = (self.log_dir / STEPS).open("w", encoding="utf-8")
        self._closed = False
        write_json_atomic(self.log_dir / META, self.meta)
        self.write(first)

    def write(self, snap: Snapshot) -> None:
        """Log one step (steps must come in increasing order)."""
        if self._last_step is not None and snap.step <= self._last_step:
            raise ValueError(f"step {snap.step} logged after step {self._last_step}")
        changed = snap.world_version != self._version
        TRUTH.write(self._truth, snap.truth if changed else None, self._parts)
        self._version = snap.world_version
        for grid in WORLD_GRIDS:
            grid.write(self._world[grid.name], getattr(snap, grid.name), self._parts)
        for track, agent in zip(self._tracks, snap.agents, strict=True):
            track.write(agent, self._parts)
        line = encode_line(SNAPSHOT_LINE, snap)
        line["agents"] = [encode_line(AGENT_LINE, a) for a in snap.agents]
        moved = self._movables.write(snap.movables)
        if moved:
            line["moved"] = moved
        self._lines.append(json.dumps(line, separators=(",", ":")))
        self._last_step = snap.step
        if len(self._lines) == self.chunk_steps:
            self._flush()

    def _flush(self) -> None:
        """Save the pending chunk, append its lines, then commit the step count in meta.json."""
        if not self._lines:
            return
        index = self.meta["steps"] // self.chunk_steps
        arrays: dict[str, Any] = chunk_arrays(self._parts)
        np.savez_compressed(self.log_dir / chunk_file(index), **arrays)
        self._steps.write("\n".join(self._lines) + "\n")
        self._steps.flush()
        self.meta["steps"] += len(self._lines)
        write_json_atomic(self.log_dir / META, self.meta)
        self._lines, self._parts = [], new_parts()

    def close(self) -> None:
        """Flush the last chunk and mark the log closed (idempotent)."""
        if not self._closed:
            self._flush()
            self._steps.close()
            self.meta["closed"], self._closed = True, True
            write_json_atomic(self.log_dir / META, self.meta)

    def __enter__(self) -> RunLogWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class RunLog:
    """A run log opened for reading: static data at once, steps streamed by :meth:`snapshots`."""

    def __init__(
        self,
        log_dir: Path,
        meta: dict[str, Any],
        truth: BoolGrid,
        terrain: TerrainGrid | None,
        prior: BeliefGrid | None = None,
        hazards: TerrainGrid | None = None,
    ) -> None:
        self.log_dir, self.meta, self.truth = log_dir, meta, truth  # truth: at step 0
        self.terrain = terrain  # true speed factors (static), None without terrain
        self.prior = prior  # the prior map robots were given, None without one
        self.hazards = hazards  # hazard zones' failure probability per cell, None without
        self.names: list[str] = [a["name"] for a in meta["agents"]]  # base first, as in snapshots
        self.robot_names = [a["name"] for a in meta["agents"] if a["kind"] == "robot"]
        self.steps: int = meta["steps"]  # committed steps (whole chunks only if never closed)

    @classmethod
    def open(cls, log_dir: Path) -> RunLog:
        """Open the log in ``log_dir``; MresimError if missing, damaged or of another version."""
        log_dir = Path(log_dir)
        if not (log_dir / META).is_file():
            raise MresimError(f"{log_dir}: no run log here (no {META}; `mresim run` writes one)")
        meta = read_meta(log_dir)
        terrain = read_static(log_dir, "terrain")
        prior = read_static(log_dir, "prior")
        hazards = read_static(log_dir, "hazards")
        log = cls(
            log_dir,
            meta,
            read_truth(log_dir, meta),
            None if terrain is None else read_only(terrain.astype(np.float32)),
            None if prior is None else read_only(prior.astype(np.uint8)),
            None if hazards is None else read_only(hazards.astype(np.float32)),
        )
        log.check_files()
        return log

    def check_files(self) -> None:
        """Every chunk the step count needs exists and steps.jsonl has enough lines."""
        for index in range(-(-self.steps // self.meta["chunk_steps"])):
            if not (self.log_dir / chunk_file(index)).is_file():
                raise damaged(self.log_dir, f"{chunk_file(index)} is missing")
        try:
            with (self.log_dir / STEPS).open(encoding="utf-8") as f:
                lines = sum(1 for _ in f)
        except (OSError, UnicodeDecodeError) as exc:
            raise damaged(self.log_dir, f"{STEPS}: {exc}") from None
        if lines < self.steps:
            raise damaged(self.log_dir, f"{STEPS} has {lines} lines, {self.steps} expected")

    def records(self) -> Iterator[tuple[dict[str, Any], Chunk, int]]:
        """Each logged step: its JSON line, its chunk's arrays and its place in the chunk."""
        per_chunk, chunk = self.meta["chunk_steps"], {}
        with (self.log_dir / STEPS).open(encoding="utf-8") as f:
            for n in range(self.steps):
                if n % per_chunk == 0:
                    chunk = self.read_chunk(n // per_chunk)
                try:
                    line = json.loads(f.readline())
                except ValueError as exc:
                    raise damaged(self.log_dir, f"{STEPS} line {n + 1}: {exc}") from None
                yield line, chunk, n % per_chunk

    def read_chunk(self, index: int) -> Chunk:
        """All arrays of delta chunk ``index``."""
        path = self.log_dir / chunk_file(index)
        try:
            with np.load(path, allow_pickle=False) as data:
                return {k: data[k] for k in data.files}
        except (OSError, ValueError, zipfile.BadZipFile) as exc:
            raise damaged(self.log_dir, f"{path.name}: {exc}") from None

    def snapshots(self) -> Iterator[Snapshot]:
        """Every logged step as a Snapshot; its grids are read-only views of the reader's
        arrays, overwritten by the next step (copy what you keep)."""
        for snap, _ in Replay(self).run():
            yield snap


def read_truth(log_dir: Path, meta: dict[str, Any]) -> BoolGrid:
    """The truth grid at step 0 (read-only)."""
    rows, cols = meta["shape"]
    try:
        with np.load(log_dir / TRUTH_FILE, allow_pickle=False) as data:
            bits = data["occupied"]
        return read_only(np.unpackbits(bits, count=rows * cols).view(bool).reshape(rows, cols))
    except (OSError, ValueError, KeyError, zipfile.BadZipFile) as exc:
        raise damaged(log_dir, f"{TRUTH_FILE}: {exc}") from None


def read_static(log_dir: Path, name: str) -> np.ndarray | None:
    """The static grid ``name`` of ``truth.npz`` (terrain, prior), None if the run had none."""
    try:
        with np.load(log_dir / TRUTH_FILE, allow_pickle=False) as data:
            return data[name] if name in data.files else None
    except (OSError, ValueError, zipfile.BadZipFile) as exc:
        raise damaged(log_dir, f"{TRUTH_FILE}: {exc}") from None


class Replay:
    """Applies a log's deltas to its own grids and recomputes each step's metrics.

    The truth follows the logged world changes; whenever it changes, the coverage counts
    against the free cells then reachable from the robots' starts, as live.
    """

    def __init__(self, log: RunLog, latest: bool | None = None) -> None:
        self.log, self.shape = log, (int(log.meta["shape"][0]), int(log.meta["shape"][1]))
        n, cells = len(log.names), self.shape[0] * self.shape[1]
        self.tracks = [Track(cells) for _ in range(n)]
        self.static = [decode_line(STATIC_AGENT, AgentSnapshot, a, n) for a in log.meta["agents"]]
        self.truth = flat_cells(log.truth)
        self.world = {g.name: np.zeros(cells, np.uint8) for g in WORLD_GRIDS}
        self.movables = MovablesTrack.from_meta(log.meta.get("movables", []))
        reachable = free_components_mask(log.truth, log.meta["starts"])
        if latest is None:  # logs before 'latest' beliefs existed were all 'grow'
            latest = log.meta.get("beliefs") == "latest"
        self.latest = latest  # 'latest' beliefs: maps can lose FREE cells (knowledge.latest)
        self.coverage: Coverage = (
            LatestCoverage(reachable, self.truth.view(bool).reshape(self.shape))
            if latest
            else Coverage(reachable)
        )
        self._maps: dict[int, BeliefGrid] = {}  # each robot's map as one stable 2-D view
        self.failures = FailureWatch(log.robot_names)
        self.fault_columns = bool(log.meta.get("fault_columns", False))
        self.known_at_base, self.first = 0.0, True
        self.version: int | None = None

    @property
    def truth_grid(self) -> BoolGrid:
        """The truth as now replayed (a read-only view, changed by later world changes)."""
        return read_only(self.truth.view(bool).reshape(self.shape))

    def run(self) -> Iterator[tuple[Snapshot, StepRecord]]:
        """Every logged step in order: its Snapshot and its recomputed metrics."""
        for n, (line, chunk, j) in enumerate(self.log.records()):
            try:
                snap, record = self.step(line, chunk, j)
            except (AttributeError, KeyError, IndexError, TypeError, ValueError) as exc:
                raise damaged(self.log.log_dir, f"logged step {n}: {exc!r}") from None
            yield snap, record

    def step(self, line: dict[str, Any], chunk: Chunk, j: int) -> tuple[Snapshot, StepRecord]:
        """Apply one logged step, entry ``j`` of its chunk."""
        n = len(self.log.names)
        fields = decode_line(SNAPSHOT_LINE, Snapshot, line, n)
        self.follow_truth(fields["world_version"], chunk, j)
        agents, free = [], []
        for i, row in enumerate(line["agents"]):
            agent, belief_changed = self.agent(i, row, chunk, j * n + i)
            agents.append(agent)
            if i > 0 and isinstance(self.coverage, LatestCoverage):
                self.touch_changed(self.coverage, i, belief_changed)
            elif i > 0:  # robots: cells newly FREE in their maps count as explored
                free.append(self.newly_free(i, belief_changed))
        record = self.measure(fields["step"], free, fields["links"], agents, fields["comm"])
        snap = Snapshot(
            **fields,
            **self.world_grids(chunk, j),  # rubble, gave_way
            movables=self.movables.read(line.get("moved", [])),
            explored=record.explored,
            known_at_base=record.known_at_base,
            alive=record.alive,
            truth=self.truth_grid,
            agents=tuple(agents),
            resolution=self.log.meta.get("resolution"),
            terrain=self.log.terrain,
            prior=self.log.prior,
            hazards=self.log.hazards,
            latest=self.latest,
            lost_knowledge=self.failures.lost_view(),
            failures=self.failures.notes(),
        )
        return snap, record

    def follow_truth(self, version: int, chunk: Chunk, j: int) -> None:
        """Apply the step's truth change, if the world changed, and retarget the coverage."""
        if self.version is not None and version != self.version:
            TRUTH.read(self.truth, chunk, j)
            self.coverage.retarget(reachable_from(self.truth_grid, self.log.meta["starts"]))
        self.version = version

    def world_grids(self, chunk: Chunk, j: int) -> dict[str, Any]:
        """The step's rubble and gave-way grids (None before the first change of the
        static walls, and in logs of version 2 or older)."""
        out: dict[str, BoolGrid | None] = {}
        for grid in WORLD_GRIDS:
            state = self.world[grid.name]
            idx = grid.read(state, chunk, j)
            out[grid.name] = None if idx is None else grid.view(state, self.shape)
        return out

    def agent(
        self, i: int, row: dict[str, Any], chunk: Chunk, k: int
    ) -> tuple[AgentSnapshot, IntArray | None]:
        """Agent ``i`` at chunk entry ``k`` (grids: read-only views of the replay's arrays)
        and the cells whose belief value changed."""
        grids, changed = self.tracks[i].read(chunk, k, self.shape)
        line = decode_line(AGENT_LINE, AgentSnapshot, row, len(self.tracks))
        return AgentSnapshot(**self.static[i], **line, **grids), changed["belief"]

    def touch_changed(self, coverage: LatestCoverage, i: int, changed: IntArray | None) -> None:
        """'latest' beliefs: recount the box of robot ``i``'s changed cells."""
        if changed is None or len(changed) == 0:
            return
        if i not in self._maps:
            self._maps[i] = self.tracks[i].grids["belief"].reshape(self.shape)
        rows, cols = np.divmod(changed, self.shape[1])
        box = (int(rows.min()), int(rows.max()) + 1, int(cols.min()), int(cols.max()) + 1)
        coverage.touch_box(self._maps[i], box)

    def newly_free(self, i: int, changed: IntArray | None) -> IntArray:
        """The cells of ``changed`` that agent ``i`` now holds FREE."""
        if changed is None:
            return np.zeros(0, np.int64)
        free: IntArray = changed[self.tracks[i].grids["belief"][changed] == FREE]
        return free

    def measure(
        self,
        step: int,
        free: list[IntArray],
        links: np.ndarray,
        agents: list[AgentSnapshot],
        comm: CommSummary,
    ) -> StepRecord:
        """The step's metrics as live (``metrics.measure_step``), from cells newly FREE."""
        self.count_free(np.concatenate([np.zeros(0, np.int64), *free]))
        self.coverage.settle()
        if self.first or links[0].any():  # the base's map changes only when it is linked
            base = self.tracks[0].grids["belief"].reshape(self.shape)
            self.known_at_base = update_known_at_base(
                self.known_at_base, base, self.coverage, not self.latest
            )
        self.first = False
        watch, coverage = self.failures, self.coverage
        base = agents[0].belief
        watch.update(step, robot_states(agents[1:]), base, coverage.reachable, coverage.total)
        return measure_step(
            step,
            self.coverage,
            self.known_at_base,
            [RobotRecord(a.name, a.distance, a.state, a.base_contact) for a in agents[1:]],
            links,
            control_links=comm.control_links,
            comm_bytes=comm.comm_bytes,
            control_bytes=comm.control_bytes,
            latency=(comm.latency_max, comm.latency_mean),
            robustness=watch.columns() if self.fault_columns else None,
        )

    def count_free(self, idx: IntArray) -> None:
        """Count cells newly FREE in some robot's map (one window of whole rows)."""
        if len(idx):
            cols = self.shape[1]
            row0, row1 = int(idx.min()) // cols, int(idx.max()) // cols + 1
            window = np.zeros((row1 - row0) * cols, dtype=bool)
            window[idx - row0 * cols] = True
            self.coverage.add_cells(window.reshape(row1 - row0, cols), row0, 0)


def reachable_from(truth: BoolGrid, starts: list[list[float]]) -> BoolGrid:
    """The free cells 4-connected to the robots' ``starts`` (``free_components_mask``), after
    a change of the world: a start a change buried under an obstacle stops seeding (as live,
    ``world.reach``); with every start buried nothing is reachable."""
    return connected_to(~truth, seed_cells(starts, truth.shape))


def recompute_metrics(log: RunLog, latest: bool | None = None) -> Iterator[StepRecord]:
    """The ``metrics.csv`` rows of the logged run, recomputed from its map deltas
    (``latest``: the run's beliefs held each cell's latest observation; None: as the log
    says)."""
    for _, record in Replay(log, latest).run():
        yield record
