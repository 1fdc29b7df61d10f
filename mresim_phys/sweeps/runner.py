"""Sweeps (sweeps, the run loop): expand a study, run what is missing, write the tables.

:func:`run_sweep` checks every arm first (nothing runs if one is wrong), locks the sweep
folder (``sweeps/lock.py``: one sweep writes a folder at a time), opens or resumes it
(``sweeps/manifest.py``), runs the missing and lost runs (and the failed ones with
``retry_failed``) on a local process pool or a Dask cluster (``sweeps/executors.py``)
under one progress bar (runs done, failed, lost, ETA; with ``verbose`` a line as each run
starts and ends), notes each finished run in the manifest as it ends, and writes
``runs.parquet`` and ``steps.parquet`` of every finished run (``sweeps/tables.py``).
"""

from __future__ import annotations

import dataclasses
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mresim_phys.output.progress import progress_bar
from mresim_phys.sweeps.executors import Backend, BackendLost, execute, make_backend
from mresim_phys.sweeps.expand import RunSpec, expand_runs, fingerprints
from mresim_phys.sweeps.lock import SweepLock
from mresim_phys.sweeps.manifest import Manifest, check_folder, clean_leftovers, open_sweep
from mresim_phys.sweeps.select import run_names, selector
from mresim_phys.sweeps.shards import shard_folder, slice_of
from mresim_phys.sweeps.study import Study, StudyError
from mresim_phys.sweeps.tables import write_runs, write_steps
from mresim_phys.sweeps.worker import FAILED, LOST, VIDEOS


@dataclass(frozen=True)
class SweepOptions:
    """How to run a sweep (the command line's flags)."""

    out: Path
    workers: int | None = None
    dask: str | None = None
    video_for: str | None = None
    verbose: bool = False
    quiet: bool = False
    backend: Backend | None = None  # a backend made by the caller (it closes it itself)
    retry_failed: bool = False  # run the runs that failed of their own error again
    shard: tuple[int, int] | None = None  # (i, N): only that slice, into OUT/shards (shards.py)


@dataclass
class SweepResult:
    """What a sweep did."""

    folder: Path
    runs: list[RunSpec]
    manifest: Manifest
    ran: int
    backend: str
    reran: int = 0  # runs run again (lost or failed before)
    lost_workers: int = 0
    stopped: str | None = None  # why the sweep stopped before its end

    @property
    def failed(self) -> list[dict[str, Any]]:
        """Records of the failed runs."""
        return self.manifest.failed()

    @property
    def lost(self) -> list[dict[str, Any]]:
        """Records of the lost runs."""
        return self.manifest.lost()

    @property
    def complete(self) -> bool:
        """Whether every run is done."""
        return not self.failed and not self.lost and self.stopped is None

    def summary(self) -> str:
        """The lines printed at the end."""
        failed, lost = self.failed, self.lost
        done = len(self.manifest.records) - len(failed) - len(lost)
        again = f"; re-ran {self.reran}" if self.reran else ""
        lines = [
            f"sweep {self.folder}: {len(self.runs)} runs, {done} done, {len(failed)} failed,"
            f" {len(lost)} lost (ran {self.ran} now on {self.backend}{again}) ->"
            f" {self.folder / 'runs.parquet'}, {self.folder / 'steps.parquet'}"
        ]
        if self.lost_workers:
            lines.append(f"  lost {self.lost_workers} worker(s) mid-run; their runs are lost")
        lines += [f"  failed {r['run_id']}: {r.get('error')} (log {r.get('log')})" for r in failed]
        lines += [f"  lost {r['run_id']}: {r.get('error')}" for r in lost]
        if self.stopped:
            lines.append(f"  stopped: {self.stopped}")
        if lost or self.stopped:
            lines.append("  run the same command again to run the lost and missing runs")
        if failed:
            lines.append("  add --retry-failed to run the failed runs again")
        return "\n".join(lines)


def with_videos(runs: list[RunSpec], text: str | None, out: Path) -> list[RunSpec]:
    """``runs`` with a video path for those ``--video-for`` selects."""
    wanted = selector(text)
    return [
        dataclasses.replace(r, video=str((out / VIDEOS / f"{r.run_id}.mp4").resolve()))
        if wanted(run_names(r.seed, r.arm, r.scenario, r.values))
        else r
        for r in runs
    ]


def run_sweep(
    study: Study, study_path: Path, study_text: str, options: SweepOptions
) -> SweepResult:
    """Run every missing run of ``study`` into ``options.out`` and write its tables."""
    runs = with_videos(expand_runs(study, study_path), options.video_for, options.out)
    if options.shard is not None:
        runs = slice_of(runs, *options.shard)
        options = dataclasses.replace(options, out=shard_folder(options.out, *options.shard))
    hashes = fingerprints(runs)
    try:
        check_folder(options.out, study.name, hashes)
    except StudyError:
        SweepLock(options.out).check()  # a sweep that is writing the folder: say so
        raise
    backend = options.backend or make_backend(options.workers, options.dask)
    try:
        options.out.mkdir(parents=True, exist_ok=True)
        with SweepLock(options.out):
            return locked_sweep(study, study_text, runs, hashes, backend, options)
    finally:
        if options.backend is None:
            backend.close()


def locked_sweep(
    study: Study,
    study_text: str,
    runs: list[RunSpec],
    hashes: dict[str, str],
    backend: Backend,
    options: SweepOptions,
) -> SweepResult:
    """The sweep, its folder locked."""
    info = {"study": study.name, "runs": hashes, "axes": list(study.axes)}
    info["reference"] = study.reference
    manifest = open_sweep(options.out, info, runs, study_text, say(options))
    todo = manifest.todo(runs, options.retry_failed)
    reran = sum(r.run_id in manifest.records for r in todo)
    ran, stopped = run_all(todo, runs, manifest, backend, options)
    clean_leftovers(options.out)  # of workers that died in this sweep
    write_runs(options.out, runs, manifest.records)
    write_steps(options.out, runs, manifest.records)
    result = SweepResult(options.out, runs, manifest, ran, backend.name, reran)
    result.lost_workers, result.stopped = backend.lost_workers, stopped
    return result


def say(options: SweepOptions) -> Callable[[str], None]:
    """Where the sweep's notes go: stderr (nowhere with ``quiet``)."""
    return (lambda text: None) if options.quiet else (lambda text: print(text, file=sys.stderr))


def run_all(
    todo: list[RunSpec],
    runs: list[RunSpec],
    manifest: Manifest,
    backend: Backend,
    options: SweepOptions,
) -> tuple[int, str | None]:
    """Run ``todo`` under one progress bar, noting each finished run in ``manifest``; how
    many finished, and why the backend could not go on (None: it ran them all)."""
    counts = {FAILED: len(manifest.failed()), LOST: len(manifest.lost()), "ran": 0}
    with progress_bar(
        total=len(runs),
        initial=len(runs) - len(todo),
        unit="run",
        desc="sweep",
        disable=options.quiet,
    ) as bar:
        bar.set_postfix(failed=counts[FAILED], lost=counts[LOST])

        def started(spec: RunSpec) -> None:
            if options.verbose:
                bar.write(f"start {spec.run_id}: {spec.label}, seed {spec.seed}")

        def finished(spec: RunSpec, record: dict[str, Any]) -> None:
            before = manifest.records.get(spec.run_id, {}).get("status")
            manifest.add(record)
            counts[FAILED] += (record["status"] == FAILED) - (before == FAILED)
            counts[LOST] += (record["status"] == LOST) - (before == LOST)
            counts["ran"] += 1
            bar.update(1)
            bar.set_postfix(failed=counts[FAILED], lost=counts[LOST])
            if options.verbose:
                took = record.get("run_time_s")
                time = f" in {took:.1f} s" if isinstance(took, (int, float)) else ""
                bar.write(f"{record['status']} {spec.run_id}{time}")

        try:
            execute(todo, str(options.out), backend, started, finished)
        except BackendLost as exc:
            return counts["ran"], str(exc)
    return counts["ran"], None
