"""Run logs (output edge): write every snapshot of a run, replay it without re-simulating.

:class:`RunLogWriter` (``output.logwriter``) streams every step's
:class:`~mresim_phys.snapshot.Snapshot` into a ``log/`` folder, every field of it as
:mod:`~mresim_phys.output.logformat` says: one JSON line per step (``steps.jsonl``: poses,
states, goals, distances, links, events, the world's version); grids (beliefs, safe space,
skeletons, and the truth when the world changed) as deltas since the previous logged step
and paths and rendezvous points in compressed chunks of ``chunk_steps`` steps
(``deltas-NNNNN.npz``); static data (``meta.json``, read back and checked by
``output.logmeta``; ``truth.npz``) once. :class:`RunLog` opens a log; :class:`Replay`
rebuilds every snapshot in order, equal to the live one field by field, with each step's
metrics recomputed by the live code (``metrics.measure_step``); :func:`recompute_metrics`
gives the rows of ``metrics.csv`` from the log alone. Layout: ``docs/run-log-format.md``.
"""

from __future__ import annotations

import json
import zipfile
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from mresim_phys.errors import MresimError
from mresim_phys.ground.grid import Ground
from mresim_phys.health_phase import step_of
from mresim_phys.knowledge.activity import with_activity
from mresim_phys.knowledge.coverage import Coverage
from mresim_phys.knowledge.health import HealthReport, HealthWatch
from mresim_phys.knowledge.latest import LatestCoverage
from mresim_phys.knowledge.robustness import FailureWatch, logged_states
from mresim_phys.metrics import RobotRecord, StepRecord, measure_step, update_known_at_base
from mresim_phys.output.logformat import (
    AGENT_LINE,
    SNAPSHOT_LINE,
    STATIC_AGENT,
    TRUTH,
    WORLD_GRIDS,
    Chunk,
    Track,
    decode_line,
)
from mresim_phys.output.logmeta import META, damaged, read_meta, read_sights
from mresim_phys.output.logworld import MovablesTrack
from mresim_phys.output.logwriter import STEPS, TRUTH_FILE, RunLogWriter, chunk_file, flat_cells
from mresim_phys.snapshot import AgentSnapshot, CommSummary, Snapshot, read_only
from mresim_phys.types import FREE, BeliefGrid, BoolGrid, IntArray
from mresim_phys.world.explorable import Explorable
from mresim_phys.world.maps import connected_to, free_components_mask, seed_cells
from mresim_phys.world.terrain import TerrainGrid

__all__ = [
    "STEPS",
    "TRUTH_FILE",
    "Replay",
    "RunLog",
    "RunLogWriter",
    "chunk_file",
    "reachable_from",
    "read_static",
    "read_truth",
    "recompute_metrics",
]


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
        grid = read_static(log_dir, "ground") if "ground" in meta else None
        # the true ground classes (ground/), None without
        self.ground = None if grid is None else Ground.from_meta(meta["ground"], read_only(grid))
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
    against the explorable area then (``world.explorable``, from the logged ``sights``,
    following the step's flipped cells) and the free cells then reachable from the
    robots' starts, as live. A log without ``sights`` (older than version 5) replays the
    metrics of its time: ``explored`` over the connected cells, no ``_connected`` columns.
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
        self.sights = read_sights(log.meta)
        truth = self.truth.view(bool).reshape(self.shape)  # writable: one compiled kernel
        ground = log.ground
        no_go = None if ground is None else ground.no_go(log.meta["ground"]["factors"])
        self.ground_grid = None if ground is None else ground.grid
        self.explorable = Explorable(truth, self.sights, no_go) if self.sights else None
        counted, connected = (
            (reachable, None) if self.explorable is None else (self.explorable.mask, reachable)
        )
        self.coverage: Coverage = (
            LatestCoverage(counted, self.truth.view(bool).reshape(self.shape), connected)
            if latest
            else Coverage(counted, connected)
        )
        self._maps: dict[int, BeliefGrid] = {}  # each robot's map as one stable 2-D view
        self.failures = FailureWatch(log.robot_names)
        self.health = HealthWatch(log.robot_names)  # idle, stuck, state reasons, as live
        self.fault_columns = bool(log.meta.get("fault_columns", False))
        self.known_at_base, self.first, self.base_heard = 0.0, True, False
        self.known_at_base_connected: float | None = None if connected is None else 0.0
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
            if i == 0:  # a delayed packet may change the base's map while it is unlinked
                self.base_heard = belief_changed is not None and len(belief_changed) > 0
            if i > 0 and isinstance(self.coverage, LatestCoverage):
                self.touch_changed(self.coverage, i, belief_changed)
            elif i > 0:  # robots: cells newly FREE in their maps count as explored
                free.append(self.newly_free(i, belief_changed))
        record = self.measure(fields["step"], free, fields["links"], agents, fields["comm"])
        record = replace(record, meetings=fields["meetings"])  # logged whole (meetings/)
        self.health.update(fields["step"], [step_of(a, self.ground_grid) for a in agents[1:]])
        self.health.note_progress(fields["step"], record.explored, record.known_at_base)
        agents[1:] = [
            replace(a, features=with_activity(a, self.health.view(a.name)[0])) for a in agents[1:]
        ]
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
            dt=self.log.meta.get("dt"),
            terrain=self.log.terrain,
            ground=self.log.ground,
            prior=self.log.prior,
            hazards=self.log.hazards,
            latest=self.latest,
            lost_knowledge=self.failures.lost_view(),
            failures=self.failures.notes(),
            sights=self.sights,
        )
        return snap, record

    def health_report(self, last: Snapshot) -> HealthReport:
        """The run-health record at the end, ``last`` being the last step replayed."""
        return self.health.report([step_of(a, self.ground_grid) for a in last.robots])

    def follow_truth(self, version: int, chunk: Chunk, j: int) -> None:
        """Apply the step's truth change, if the world changed, and retarget the coverage."""
        if self.version is not None and version != self.version:
            flipped = TRUTH.read(self.truth, chunk, j)
            connected = reachable_from(self.truth_grid, self.log.meta["starts"])
            if self.explorable is None:
                self.coverage.retarget(connected)
            else:
                self.coverage.retarget_connected(connected)
                if flipped is not None and len(flipped):
                    self.follow_explorable(self.explorable, flipped)
        self.version = version

    def follow_explorable(self, explorable: Explorable, flipped: IntArray) -> None:
        """The explorable area follows the cells a logged truth change flipped."""
        rows, cols = np.divmod(flipped, self.shape[1])
        box = (int(rows.min()), int(rows.max()) + 1, int(cols.min()), int(cols.max()) + 1)
        flips = np.zeros((box[1] - box[0], box[3] - box[2]), dtype=bool)
        flips[rows - box[0], cols - box[2]] = True
        window, held = explorable.update(self.truth.view(bool).reshape(self.shape), box, flips)
        self.coverage.retarget(explorable.mask, window, held)

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
        # the base's map changes only when it is linked or a delayed packet lands there
        if self.first or links[0].any() or self.base_heard:
            base = self.tracks[0].grids["belief"].reshape(self.shape)
            known = (self.known_at_base, self.known_at_base_connected)
            known = update_known_at_base(known, base, self.coverage, not self.latest)
            self.known_at_base, self.known_at_base_connected = known
        self.first = False
        watch, coverage = self.failures, self.coverage
        base = agents[0].belief
        watch.update(step, logged_states(agents[1:]), base, coverage.reachable, coverage.total)
        return measure_step(
            step,
            self.coverage,
            self.known_at_base,
            [
                RobotRecord(a.name, a.distance, a.state, a.base_contact, a.features)
                for a in agents[1:]
            ],
            links,
            control_links=comm.control_links,
            comm_bytes=comm.comm_bytes,
            control_bytes=comm.control_bytes,
            latency=(comm.latency_max, comm.latency_mean),
            robustness=watch.columns() if self.fault_columns else None,
            known_at_base_connected=self.known_at_base_connected,
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
