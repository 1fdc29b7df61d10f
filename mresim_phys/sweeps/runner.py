"""Sweeps (sweeps, the run loop): expand a study, run what is missing, write the tables.

:func:`run_sweep` checks every arm first (nothing runs if one is wrong), opens or resumes
the sweep folder (``sweeps/manifest.py``), runs the missing runs on a local process pool
or a Dask cluster (``sweeps/executors.py``) under one progress bar (runs done, failed,
ETA; with ``verbose`` a line as each run starts and ends), notes each finished run in the
manifest as it ends, and writes ``runs.parquet`` and ``steps.parquet`` of every finished
run (``sweeps/tables.py``).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tqdm import tqdm

from mresim_phys.sweeps.executors import Backend, execute, make_backend
from mresim_phys.sweeps.expand import RunSpec, expand_runs, fingerprints
from mresim_phys.sweeps.manifest import Manifest, check_folder, open_sweep
from mresim_phys.sweeps.select import run_names, selector
from mresim_phys.sweeps.study import Study
from mresim_phys.sweeps.tables import write_runs, write_steps
from mresim_phys.sweeps.worker import FAILED, VIDEOS


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


@dataclass
class SweepResult:
    """What a sweep did."""

    folder: Path
    runs: list[RunSpec]
    manifest: Manifest
    ran: int
    backend: str

    @property
    def failed(self) -> list[dict[str, Any]]:
        """Records of the failed runs."""
        return self.manifest.failed()

    def summary(self) -> str:
        """The lines printed at the end."""
        done = len(self.manifest.records) - len(self.failed)
        lines = [
            f"sweep {self.folder}: {len(self.runs)} runs, {done} done, {len(self.failed)} failed"
            f" (ran {self.ran} now on {self.backend}) -> {self.folder / 'runs.parquet'},"
            f" {self.folder / 'steps.parquet'}"
        ]
        lines += [f"  failed {r['run_id']}: {r['error']} (log {r['log']})" for r in self.failed]
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
    hashes = fingerprints(runs)
    check_folder(options.out, study.name, hashes)
    backend = options.backend or make_backend(options.workers, options.dask)
    try:
        info = {
            "study": study.name,
            "runs": hashes,
            "axes": list(study.axes),
            "reference": study.reference,
        }
        manifest = open_sweep(options.out, info, runs, study_text)
        todo = manifest.todo(runs)
        run_all(todo, runs, manifest, backend, options)
    finally:
        if options.backend is None:
            backend.close()
    write_runs(options.out, runs, manifest.records)
    write_steps(options.out, runs, manifest.records)
    return SweepResult(options.out, runs, manifest, len(todo), backend.name)


def run_all(
    todo: list[RunSpec],
    runs: list[RunSpec],
    manifest: Manifest,
    backend: Backend,
    options: SweepOptions,
) -> None:
    """Run ``todo`` under one progress bar, noting each finished run in ``manifest``."""
    failed = len(manifest.failed())
    with tqdm(
        total=len(runs),
        initial=len(runs) - len(todo),
        unit="run",
        desc="sweep",
        disable=options.quiet,
    ) as bar:
        bar.set_postfix(failed=failed)

        def started(spec: RunSpec) -> None:
            if options.verbose:
                bar.write(f"start {spec.run_id}: {spec.label}, seed {spec.seed}")

        def finished(spec: RunSpec, record: dict[str, Any]) -> None:
            nonlocal failed
            manifest.add(record)
            failed += record["status"] == FAILED
            bar.update(1)
            bar.set_postfix(failed=failed)
            if options.verbose:
                bar.write(f"{record['status']} {spec.run_id} in {record['run_time_s']:.1f} s")

        execute(todo, str(options.out), backend, started, finished)
