"""Run sessions (output edge): the one loop over a run's steps, feeding every recorder.

:func:`run_session` is the only loop of a command-line run: it takes each step's
record from ``Simulation.iterate()`` and hands it, with a lazily built snapshot,
to each recorder (``output.recorders``: metrics files, run log, video, PNG snapshots).
Rendering never happens inside ``Simulation.step()``.

Everything goes into a fresh temporary folder beside the output folder, moved into place
at the end (``output.rundir``), so a reused output folder never mixes two runs. SIGINT and
SIGTERM (``output.signals``) stop the run at the end of the current step: every recorder
is closed, ``final.png`` and ``summary.json`` (``stop_reason`` ``"interrupted"`` and the
``signal``) are written and the folder is moved into place, as for a finished run.

A run that fails (a file that cannot be written, a full disk: ``output.files``; or any
error) discards its recorders (the unfinished video is deleted) and its temporary folder;
``<out>`` keeps what it held. A WriteError names the file under its final name
(``<out>/metrics.csv``, not the temporary folder's).
"""

from __future__ import annotations

import contextlib
import signal
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

from mresim_phys.metrics import StepRecord
from mresim_phys.output.files import WriteError
from mresim_phys.output.health import run_health
from mresim_phys.output.localization import PoseRecorder, localization_summary
from mresim_phys.output.meetings import meetings_summary
from mresim_phys.output.physical import physical_summary
from mresim_phys.output.readings import readings_summary
from mresim_phys.output.recorders import Recorder, SnapshotSource, make_recorders, summarise
from mresim_phys.output.robustness import check_paired, run_robustness, write_robustness
from mresim_phys.output.rundir import StagedRun
from mresim_phys.output.signals import StopRequest, stop_on_signals
from mresim_phys.output.team import team_summary
from mresim_phys.sim import Simulation
from mresim_phys.snapshot import Snapshot
from mresim_phys.tracking import explorable_summary

INTERRUPTED = "interrupted"


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
    """What a session produced (``signal``: the signal that interrupted it, if any)."""

    summary: dict[str, object]
    out_dir: Path
    video: Path | None
    reason: str
    signal: str | None = None
    exit_status: int = 0


def run_session(
    sim: Simulation,
    out_dir: Path,
    on_step: Callable[[StepRecord], None] | None = None,
    *,
    overwrite: bool = False,
    stop: StopRequest | None = None,
    finish: Callable[[Path], object] | None = None,
) -> Outcome:
    """Run ``sim`` to its end (or to a stop signal) into ``out_dir``, feeding every recorder.

    Args:
        sim: The simulation, at step 0.
        out_dir: The run folder; refused (MresimError) if it holds a run of another
            scenario or is no run folder, unless ``overwrite``.
        on_step: Called with every step's record (a progress bar).
        overwrite: Replace ``out_dir`` whatever it holds.
        stop: A StopRequest whose signal handlers the caller installed; None: install
            handlers for SIGINT and SIGTERM for the session (and restore them after).
        finish: Called with the (temporary) run folder once summary.json is written, before
            the folder moves into place (the CLI draws its plots there).
    """
    if stop is None:
        with stop_on_signals() as own:
            return run_session(sim, out_dir, on_step, overwrite=overwrite, stop=own, finish=finish)
    check_paired(sim)
    staged = StagedRun(out_dir, sim.scenario.name, overwrite)
    try:
        outcome = record_run(sim, staged.folder, on_step, stop)
        if finish is not None:
            finish(staged.folder)
        staged.commit()
    except WriteError as exc:
        staged.discard()
        raise exc.moved(staged.folder, staged.target, abandoned(staged.target)) from exc
    except BaseException:
        staged.discard()
        raise
    return replace(outcome, out_dir=Path(out_dir))


def abandoned(out_dir: Path) -> str:
    """What a WriteError of a run adds: what became of the run and what to do."""
    return (
        f"The run stopped: {out_dir} still holds what it held before (an earlier run, or"
        " nothing), no file is left half-written, files already finished (a video) are"
        " kept. Free some space on that disk, or give another --out or --video PATH, and"
        " run again."
    )


def record_run(
    sim: Simulation,
    folder: Path,
    on_step: Callable[[StepRecord], None] | None,
    stop: StopRequest,
) -> Outcome:
    """Feed every step to the recorders writing into ``folder``; close them; write the summary."""
    writer, recorders, video = make_recorders(sim, folder)
    started = time.perf_counter()
    try:
        step_until_stopped(sim, recorders, on_step, stop)
    except KeyboardInterrupt:  # no handler of ours was installed (not the main thread, ...)
        stop.signum = stop.signum or int(signal.SIGINT)
    except BaseException:
        discard_all(recorders)
        raise
    close_all(recorders)
    elapsed = time.perf_counter() - started
    natural = sim.stop_reason()
    reason = natural if natural is not None else INTERRUPTED
    summary = summarise(sim.scenario, sim.record, sim.milestones, elapsed, reason, sim.comm_totals)
    summary |= run_robustness(sim) | run_health(sim)
    summary |= explorable_summary(sim.coverage, sim.record, sim.milestones)
    summary |= physical_summary(sim)  # seconds and metres, when the scenario gives dt
    poses = next((r for r in recorders if isinstance(r, PoseRecorder)), None)
    summary |= localization_summary(sim, poses) | readings_summary(sim) | team_summary(sim)
    summary |= meetings_summary(sim)  # a run whose strategies plan meetings
    interrupted = reason == INTERRUPTED
    if interrupted:
        summary["signal"] = stop.name
    writer.write_summary(summary)
    if not interrupted:
        write_robustness(sim, folder, stop)
    status = stop.exit_status if interrupted else 0
    return Outcome(summary, folder, video, reason, stop.name if interrupted else None, status)


def close_all(recorders: list[Recorder]) -> None:
    """Close every recorder; if one fails, discard the ones after it and raise."""
    for n, recorder in enumerate(recorders):
        try:
            recorder.close()
        except BaseException:
            discard_all(recorders[n + 1 :])
            raise


def discard_all(recorders: list[Recorder]) -> None:
    """The run failed: discard every recorder (their own failures would only hide it)."""
    for recorder in recorders:
        with contextlib.suppress(Exception):
            recorder.discard()


def step_until_stopped(
    sim: Simulation,
    recorders: list[Recorder],
    on_step: Callable[[StepRecord], None] | None,
    stop: StopRequest,
) -> None:
    """Hand every step to the recorders until the run ends or a stop signal arrived."""
    for record in sim.iterate():
        snapshot = once(sim.snapshot)
        for recorder in recorders:
            recorder.on_step(record, snapshot)
        if on_step is not None:
            on_step(record)
        if stop.requested:
            return
