"""Run logs (output edge): :class:`RunLogWriter` streams a run's snapshots into a log folder.

Every field of every step goes where ``output.logformat`` says (``output.runlog`` reads it
back; layout: ``docs/run-log-format.md``). Chunks, ``truth.npz`` and ``meta.json`` are
written whole or not at all (``output.files``); ``steps.jsonl`` is appended to and flushed
to the disk before ``meta.json`` commits a chunk. A write that fails raises WriteError and
leaves the log as its last commit says (``closed: false``): the writer commits nothing
more, even when closed.
"""

from __future__ import annotations

import contextlib
import json
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from mresim_phys.ground.feature import GROUND
from mresim_phys.ground.grid import ground_meta
from mresim_phys.output.files import WriteError, atomic_path, cause_of, write_json_atomic
from mresim_phys.output.logformat import (
    AGENT_LINE,
    FORMAT,
    SNAPSHOT_LINE,
    STATIC_AGENT,
    TRUTH,
    VERSION,
    WORLD_GRIDS,
    Track,
    chunk_arrays,
    encode_line,
    new_parts,
    point,
)
from mresim_phys.output.logmeta import META, sight_meta
from mresim_phys.output.logworld import MovablesTrack, movable_meta
from mresim_phys.snapshot import Snapshot

TRUTH_FILE, STEPS = "truth.npz", "steps.jsonl"


def chunk_file(index: int) -> str:
    """File name of delta chunk ``index`` (logged steps index*K .. index*K + K-1)."""
    return f"deltas-{index:05d}.npz"


def new_meta(
    first: Snapshot,
    name: str,
    seed: int,
    chunk_steps: int,
    faults: bool = False,
    columns: Sequence[str] = (),
) -> dict[str, Any]:
    """meta.json of a log about to get its first step (``fault_columns``: the run had
    faults, so its metrics.csv has the robustness columns; only written when true;
    ``columns``: the optional metric columns its scenario named, only written when some)."""
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
    if columns:
        meta["columns"] = list(columns)
    if first.sights:
        meta["sights"] = [sight_meta(s) for s in first.sights]
    if first.dt is not None:  # a run given in seconds too (scenario dt)
        meta["dt"] = first.dt
    if first.ground is not None:  # the classes (the grid is in truth.npz) and who crosses what
        crossings = [GROUND.of(a) for a in first.robots]
        factors = [list(c.factors) for c in crossings if c is not None]
        meta["ground"] = ground_meta(first.ground, factors)
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
        columns: Sequence[str] = (),
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
        self.meta = new_meta(first, name, seed, chunk_steps, faults, columns)
        truth = np.packbits(first.truth, axis=None)
        statics: dict[str, Any] = {"occupied": truth}
        if first.terrain is not None:
            statics["terrain"] = first.terrain
        if first.ground is not None:
            statics["ground"] = first.ground.grid
        if first.prior is not None:
            statics["prior"] = first.prior
        if first.hazards is not None:
            statics["hazards"] = first.hazards
        with atomic_path(self.log_dir / TRUTH_FILE) as tmp:
            np.savez_compressed(tmp, **statics)
        self._tracks = [Track(cells) for _ in first.agents]
        self._truth = flat_cells(np.asarray(first.truth, dtype=bool))
        self._world = {g.name: np.zeros(cells, np.uint8) for g in WORLD_GRIDS}
        self._movables = MovablesTrack(first.movables)
        self._version = first.world_version
        self._lines: list[str] = []
        self._parts = new_parts()
        self._last_step: int | None = None
        try:
            self._steps = (self.log_dir / STEPS).open("w", encoding="utf-8")
        except OSError as exc:
            raise WriteError(self.log_dir / STEPS, cause_of(exc)) from exc
        self._closed = self._failed = False
        write_json_atomic(self.log_dir / META, self.meta)
        self.write(first)

    def write(self, snap: Snapshot) -> None:
        """Log one step (steps must come in increasing order)."""
        if self._failed or self._closed:
            raise ValueError(f"run log {self.log_dir} is closed or failed to write")
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
        """Save the pending chunk, append its lines, then commit the step count in meta.json
        (after a failure: mark the writer failed and raise)."""
        if not self._lines:
            return
        try:
            self._save_chunk()
        except BaseException:
            self._failed = True
            raise
        self._lines, self._parts = [], new_parts()

    def _save_chunk(self) -> None:
        index = self.meta["steps"] // self.chunk_steps
        arrays: dict[str, Any] = chunk_arrays(self._parts)
        with atomic_path(self.log_dir / chunk_file(index)) as tmp:
            np.savez_compressed(tmp, **arrays)
        try:
            self._steps.write("\n".join(self._lines) + "\n")
            self._steps.flush()
            os.fsync(self._steps.fileno())
        except OSError as exc:
            raise WriteError(self.log_dir / STEPS, cause_of(exc)) from exc
        meta = {**self.meta, "steps": self.meta["steps"] + len(self._lines)}
        write_json_atomic(self.log_dir / META, meta)
        self.meta = meta

    def close(self) -> None:
        """Flush the last chunk and mark the log closed (idempotent). After a failed write
        only the file is released: the log stays as its last commit says."""
        if self._closed:
            return
        self._closed = True
        try:
            if not self._failed:
                self._flush()
                meta = {**self.meta, "closed": True}
                write_json_atomic(self.log_dir / META, meta)
                self.meta = meta
        finally:
            with contextlib.suppress(OSError):  # flushed by _flush; after a failure: past it
                self._steps.close()

    def abandon(self) -> None:
        """Release the files without committing more: the log keeps ``closed: false`` and
        the steps it committed (what a failed run does; idempotent)."""
        self._failed = True
        self.close()

    def __enter__(self) -> RunLogWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
