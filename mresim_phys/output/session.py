"""Run sessions (output edge): the one loop over a run's steps, feeding every recorder.

:func:`run_session` is the only loop of a command-line run: it takes each step's
record from ``Simulation.iterate()`` and hands it, with a lazily built snapshot,
to each recorder (``output.recorders``: metrics files, run log, video, PNG snapshots).
Rendering never happens inside ``Simulation.step()``. An interrupted run still closes
every recorder, so nothing already written is lost.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from mresim_phys.metrics import StepRecord
from mresim_phys.output.recorders import SnapshotSource, make_recorders, summarise
from mresim_phys.sim import Simulation
from mresim_phys.snapshot import Snapshot


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


def run_session(
    sim: Simulation, out_dir: Path, on_step: Callable[[StepRecord], None] | None = None
) -> Outcome:
    """Run ``sim`` to its end, feeding every recorder; write summary.json."""
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
