"""Run logs (output edge: run logs): replay a run without re-simulating it.

:class:`RunLogWriter` streams every step's :class:`~mresim_phys.snapshot.Snapshot`
into a ``log/`` folder: poses, states, goals, distances, links and events as one
JSON line per step (``steps.jsonl``); map changes as deltas (cells whose belief
value or safe flag changed since the previous logged step) and paths in
compressed chunks of ``chunk_steps`` steps (``deltas-NNNNN.npz``); static data
(``meta.json``, ``truth.npz``) once. :class:`RunLog` reads a log and rebuilds
every snapshot in order; :func:`recompute_metrics` recomputes the rows of
``metrics.csv`` from the log alone. Layout: ``docs/run-log-format.md``.
"""

from __future__ import annotations

import json
import os
import zipfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from mresim_phys.errors import MresimError
from mresim_phys.knowledge.mapping import Coverage
from mresim_phys.metrics import RobotRecord, StepRecord
from mresim_phys.snapshot import AgentSnapshot, CommSummary, Snapshot, read_only
from mresim_phys.types import FREE, BoolGrid, IntArray
from mresim_phys.world.maps import free_components_mask

FORMAT, VERSION = "mresim-runlog", 1
META, TRUTH, STEPS = "meta.json", "truth.npz", "steps.jsonl"
NEW_PATH = -1  # path_keep value: the path's points are stored in the chunk
Chunk = dict[str, np.ndarray]
PARTS = {"belief_idx": np.int32, "belief_val": np.uint8, "safe_idx": np.int32}
PARTS |= {"path_keep": np.int32, "path_xy": np.float64}
OFFSETS = ("belief_idx", "safe_idx", "path_xy")  # belief_val shares belief_off


def chunk_file(index: int) -> str:
    """File name of delta chunk ``index`` (logged steps index*K .. index*K + K-1)."""
    return f"deltas-{index:05d}.npz"


def diff_into(copy: np.ndarray, grid: np.ndarray) -> IntArray:
    """Sorted flat indices where ``grid`` (uint8 or bool) differs from ``copy``; ``copy`` is
    then updated to match. Compares 8 bytes at a time, then the bytes of differing words."""
    cur = np.ascontiguousarray(grid).reshape(-1).view(np.uint8)
    n = copy.size - copy.size % 8
    words = np.flatnonzero(copy[:n].view(np.uint64) != cur[:n].view(np.uint64))
    candidates = (words[:, None] * 8 + np.arange(8)).ravel()
    hits = candidates[copy[candidates] != cur[candidates]]
    idx = np.concatenate((hits, n + np.flatnonzero(copy[n:] != cur[n:])))
    copy[idx] = cur[idx]
    return idx


def new_meta(first: Snapshot, name: str, seed: int, chunk_steps: int) -> dict[str, Any]:
    """meta.json of a log about to get its first step."""
    return {
        "format": FORMAT,
        "version": VERSION,
        "name": name,
        "seed": seed,
        "shape": list(first.truth.shape),
        "resolution": first.resolution,
        "chunk_steps": chunk_steps,
        "agents": [static_row(a) for a in first.agents],
        "starts": [point(a.position) for a in first.robots],
        "steps": 0,
        "closed": False,
    }


def static_row(agent: AgentSnapshot) -> dict[str, Any]:
    """The part of an agent that never changes during a run."""
    sizes = {"radius": float(agent.radius), "comm_range": float(agent.comm_range)}
    return {"name": agent.name, "kind": agent.kind, **sizes}


def point(value: Any) -> list[float] | None:
    """An (x, y) pair as a JSON list of full-precision floats."""
    return None if value is None else [float(value[0]), float(value[1])]


def agent_line(agent: AgentSnapshot) -> dict[str, Any]:
    """The per-step part of an agent, keyed by AgentSnapshot field (path and grids: chunk)."""
    pose = {"position": point(agent.position), "heading": float(agent.heading)}
    row = {**pose, "state": agent.state, "role": agent.role, "goal": point(agent.goal)}
    row["distance"] = float(agent.distance)
    if agent.kind == "robot":
        row["base_contact"] = int(agent.base_contact)
    if agent.parent is not None:
        row["parent"] = agent.parent
    return row


def path_keep(prev: np.ndarray, cur: np.ndarray) -> int:
    """``len(cur)`` if ``cur`` is the tail of ``prev`` (a path being followed), else NEW_PATH."""
    keep = len(cur)
    same = keep <= len(prev) and np.array_equal(prev[len(prev) - keep :], cur)
    return keep if same else NEW_PATH


def offsets(parts: list[np.ndarray]) -> np.ndarray:
    """Where each part starts in the concatenation, then the total length."""
    return np.concatenate(([0], np.cumsum([len(p) for p in parts], dtype=np.int64)))


def chunk_arrays(parts: dict[str, list[np.ndarray]]) -> Chunk:
    """The parts gathered for a chunk as the arrays of its ``.npz`` file, with offsets."""
    arrays = {k: np.concatenate(v).astype(PARTS[k]) for k, v in parts.items()}
    return arrays | {f"{k.split('_')[0]}_off": offsets(parts[k]) for k in OFFSETS}


def write_json(path: Path, data: dict[str, Any]) -> None:
    """Write ``data`` as JSON to ``path`` atomically (temporary file, then rename)."""
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(data, indent=2) + "\n", encoding="utf-8")
    os.replace(tmp, path)


class RunLogWriter:
    """Streams a run's snapshots into ``log_dir``; ``first`` (step 0) is logged at once."""

    def __init__(
        self, log_dir: Path, first: Snapshot, *, name: str, seed: int, chunk_steps: int = 100
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
        self.meta = new_meta(first, name, seed, chunk_steps)
        np.savez_compressed(self.log_dir / TRUTH, occupied=np.packbits(first.truth, axis=None))
        self._belief = [np.zeros(cells, np.uint8) for _ in first.agents]
        self._safe = [np.zeros(cells, np.uint8) for _ in first.agents]
        self._paths = [np.zeros((0, 2)) for _ in first.agents]
        self._lines: list[str] = []
        self._parts: dict[str, list[np.ndarray]] = {k: [] for k in PARTS}
        self._last_step: int | None = None
        self._steps = (self.log_dir / STEPS).open("w", encoding="utf-8")
        self._closed = False
        write_json(self.log_dir / META, self.meta)
        self.write(first)

    def write(self, snap: Snapshot) -> None:
        """Log one step (steps must come in increasing order)."""
        if self._last_step is not None and snap.step <= self._last_step:
            raise ValueError(f"step {snap.step} logged after step {self._last_step}")
        for i, agent in enumerate(snap.agents):
            idx = diff_into(self._belief[i], agent.belief)
            flips = diff_into(self._safe[i], agent.safe)
            path = np.array(agent.path, dtype=np.float64).reshape(-1, 2)
            keep = path_keep(self._paths[i], path)
            self._paths[i] = path
            parts = (np.diff(idx, prepend=0), self._belief[i][idx], np.diff(flips, prepend=0))
            parts += (np.array([keep]), path if keep == NEW_PATH else path[:0])
            for name, part in zip(PARTS, parts, strict=True):  # indices as gaps: compress well
                self._parts[name].append(part)
        line = {"step": snap.step, "events": list(snap.events)}
        line["links"] = np.flatnonzero(snap.links).tolist()
        line["comm"] = snap.comm.to_json()
        line["agents"] = [agent_line(a) for a in snap.agents]
        self._lines.append(json.dumps(line, separators=(",", ":")))
        self._last_step = snap.step
        if len(self._lines) == self.chunk_steps:
            self._flush()

    def _flush(self) -> None:
        """Save the pending chunk, append its lines, then commit the step count in meta.json."""
        if not self._lines:
            return
        index = self.meta["steps"] // self.chunk_steps
        np.savez_compressed(self.log_dir / chunk_file(index), **chunk_arrays(self._parts))
        self._steps.write("\n".join(self._lines) + "\n")
        self._steps.flush()
        self.meta["steps"] += len(self._lines)
        write_json(self.log_dir / META, self.meta)
        self._lines, self._parts = [], {k: [] for k in PARTS}

    def close(self) -> None:
        """Flush the last chunk and mark the log closed (idempotent)."""
        if not self._closed:
            self._flush()
            self._steps.close()
            self.meta["closed"], self._closed = True, True
            write_json(self.log_dir / META, self.meta)

    def __enter__(self) -> RunLogWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def damaged(log_dir: Path, what: str) -> MresimError:
    """The error for an unreadable log."""
    return MresimError(f"{log_dir}: the run log is damaged ({what}); re-run to write a new one.")


class RunLog:
    """A run log opened for reading: static data at once, steps streamed by :meth:`snapshots`."""

    def __init__(self, log_dir: Path, meta: dict[str, Any], truth: BoolGrid) -> None:
        self.log_dir, self.meta, self.truth = log_dir, meta, truth
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
        log = cls(log_dir, meta, read_truth(log_dir, meta))
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


def read_meta(log_dir: Path) -> dict[str, Any]:
    """meta.json, checked for format, version and required keys."""
    try:
        meta = json.loads((log_dir / META).read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise damaged(log_dir, f"{META}: {exc}") from None
    if not isinstance(meta, dict) or meta.get("format") != FORMAT:
        raise damaged(log_dir, f"{META} is not a {FORMAT} file")
    if meta.get("version") != VERSION:
        raise MresimError(
            f"{log_dir}: run log format version {meta.get('version')!r}; this mresim reads"
            f" version {VERSION}. Re-run the scenario or use a matching mresim."
        )
    missing = {"shape", "chunk_steps", "agents", "starts", "steps"} - meta.keys()
    if missing:
        raise damaged(log_dir, f"{META} lacks {sorted(missing)}")
    return meta


def read_truth(log_dir: Path, meta: dict[str, Any]) -> BoolGrid:
    """The truth grid (read-only)."""
    rows, cols = meta["shape"]
    try:
        with np.load(log_dir / TRUTH, allow_pickle=False) as data:
            bits = data["occupied"]
        return read_only(np.unpackbits(bits, count=rows * cols).view(bool).reshape(rows, cols))
    except (OSError, ValueError, KeyError, zipfile.BadZipFile) as exc:
        raise damaged(log_dir, f"{TRUTH}: {exc}") from None


def segment(chunk: Chunk, kind: str, k: int) -> slice:
    """Entry ``k`` (step-in-chunk * agents + agent) of a chunk's ``kind`` arrays."""
    return slice(int(chunk[f"{kind}_off"][k]), int(chunk[f"{kind}_off"][k + 1]))


class Replay:
    """Applies a log's deltas to its own grids and recomputes each step's metrics."""

    def __init__(self, log: RunLog) -> None:
        self.log, self.shape, n = log, tuple(log.meta["shape"]), len(log.names)
        cells = self.shape[0] * self.shape[1]
        self.belief = [np.zeros(cells, np.uint8) for _ in range(n)]
        self.safe = [np.zeros(cells, np.uint8) for _ in range(n)]
        self.paths = [read_only(np.zeros((0, 2))) for _ in range(n)]
        self.coverage = Coverage(free_components_mask(log.truth, log.meta["starts"]))
        self.known_at_base, self.first = 0.0, True

    def run(self) -> Iterator[tuple[Snapshot, StepRecord]]:
        """Every logged step in order: its Snapshot and its recomputed metrics."""
        for n, (line, chunk, j) in enumerate(self.log.records()):
            try:
                snap, record = self.step(line, chunk, j)
            except (KeyError, IndexError, TypeError, ValueError) as exc:
                raise damaged(self.log.log_dir, f"logged step {n}: {exc!r}") from None
            yield snap, record

    def step(self, line: dict[str, Any], chunk: Chunk, j: int) -> tuple[Snapshot, StepRecord]:
        """Apply one logged step, entry ``j`` of its chunk."""
        n = len(self.log.names)
        free = [self.apply(i, chunk, j * n + i) for i in range(n)]
        links = np.isin(np.arange(n * n), line["links"]).reshape(n, n)
        agents = tuple(self.agent(i, row) for i, row in enumerate(line["agents"]))
        comm = CommSummary.from_json(line.get("comm"), n)
        record = self.measure(line["step"], free[1:], links, agents, comm)  # robots: 1..n-1
        snap = Snapshot(
            step=line["step"],
            explored=record.explored,
            known_at_base=record.known_at_base,
            alive=record.alive,
            truth=self.log.truth,
            agents=agents,
            links=links,
            events=tuple(line["events"]),
            resolution=self.log.meta.get("resolution"),
            comm=comm,
        )
        return snap, record

    def apply(self, i: int, chunk: Chunk, k: int) -> IntArray:
        """Apply agent ``i``'s deltas and path; return the cells that became FREE."""
        part = segment(chunk, "belief", k)
        idx = np.cumsum(chunk["belief_idx"][part], dtype=np.int64)
        self.belief[i][idx] = chunk["belief_val"][part]
        flips = np.cumsum(chunk["safe_idx"][segment(chunk, "safe", k)], dtype=np.int64)
        self.safe[i][flips] ^= 1
        keep, prev = int(chunk["path_keep"][k]), self.paths[i]
        if keep == NEW_PATH:
            self.paths[i] = read_only(chunk["path_xy"][segment(chunk, "path", k)])
        else:
            self.paths[i] = prev[len(prev) - keep :]
        return idx[chunk["belief_val"][part] == FREE]

    def agent(self, i: int, row: dict[str, Any]) -> AgentSnapshot:
        """Agent ``i`` of a step, its grids as read-only views of the replay's arrays."""
        row = {**row, "position": tuple(row["position"])}
        row["goal"] = None if row["goal"] is None else tuple(row["goal"])
        belief = read_only(self.belief[i].reshape(self.shape))
        safe = read_only(self.safe[i].view(bool).reshape(self.shape))
        static = self.log.meta["agents"][i]
        return AgentSnapshot(**static, **row, belief=belief, safe=safe, path=self.paths[i])

    def measure(
        self,
        step: int,
        free: list[IntArray],
        links: np.ndarray,
        agents: tuple[AgentSnapshot, ...],
        comm: CommSummary,
    ) -> StepRecord:
        """The step's metrics as ``Simulation.measure`` computes them, from cells newly FREE."""
        self.count_free(np.concatenate([np.zeros(0, np.int64), *free]))
        if self.first or links[0].any():  # the base's map changes only when it is linked
            base = self.belief[0].reshape(self.shape)
            known = np.count_nonzero((base == FREE) & self.coverage.reachable)
            fraction = known / self.coverage.total if self.coverage.total else 1.0
            self.known_at_base = float(max(self.known_at_base, min(fraction, 1.0)))
        self.first = False
        robots = tuple(RobotRecord(a.name, a.distance, a.state, a.base_contact) for a in agents[1:])
        control = 0 if comm.control_links is None else int(np.triu(comm.control_links).sum())
        return StepRecord(
            step=step,
            explored=min(self.coverage.fraction, 1.0),
            known_at_base=self.known_at_base,
            distance=sum(r.distance for r in robots),
            alive=sum(r.state != "failed" for r in robots),
            links=int(np.triu(links).sum()),
            robots=robots,
            comm_bytes=comm.comm_bytes,
            control_links=control,
            control_bytes=comm.control_bytes,
            latency_max=comm.latency_max,
            latency_mean=comm.latency_mean,
        )

    def count_free(self, idx: IntArray) -> None:
        """Count cells newly FREE in some robot's map (one window of whole rows)."""
        if len(idx):
            cols = self.shape[1]
            row0, row1 = int(idx.min()) // cols, int(idx.max()) // cols + 1
            window = np.zeros((row1 - row0) * cols, dtype=bool)
            window[idx - row0 * cols] = True
            self.coverage.add_cells(window.reshape(row1 - row0, cols), row0, 0)


def recompute_metrics(log: RunLog) -> Iterator[StepRecord]:
    """The ``metrics.csv`` rows of the logged run, recomputed from its map deltas."""
    for _, record in Replay(log).run():
        yield record
