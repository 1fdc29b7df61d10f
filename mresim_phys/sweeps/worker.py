"""Sweep worker (sweeps, output edge): one run of a sweep, in any process or Dask worker.

:func:`run_task` builds the run's scenario from its plain data, runs it with the same
session as ``mresim run`` (``output/session.py``: every file written into a temporary
sibling folder, renamed into ``<sweep>/runs/<run_id>`` when complete) and returns a small
result record. While it runs, its marker ``<sweep>/inflight/<run_id>.json`` names the
process (``sweeps/inflight.py``). A run that raises leaves no run folder; its traceback
goes to ``<sweep>/errors/<run_id>.log`` and the result says ``failed`` (the run's own
error: a bug in a strategy, say), or ``lost`` when the machine failed it (a full disk:
``OSError`` or ``output.files.WriteError``; ``MemoryError``): lost runs are run again on
resume. The sweep goes on either way.
"""

from __future__ import annotations

import contextlib
import time
import traceback
from pathlib import Path
from typing import Any

from mresim_phys.output.files import WriteError, write_text_atomic
from mresim_phys.output.session import run_session
from mresim_phys.output.signals import StopRequest
from mresim_phys.sim import Simulation
from mresim_phys.sweeps.expand import RunSpec
from mresim_phys.sweeps.inflight import in_flight

RUNS = "runs"
ERRORS = "errors"
VIDEOS = "videos"
DONE, FAILED, LOST = "done", "failed", "lost"
STATUSES = (DONE, FAILED, LOST)
OUTSIDE = (OSError, WriteError, MemoryError)  # errors of the machine, not of the run


def run_folder(sweep: Path, run_id: str) -> Path:
    """Where a sweep's run ``run_id`` lives."""
    return Path(sweep) / RUNS / run_id


def error_log(sweep: Path, run_id: str) -> Path:
    """Where the traceback of a failed run goes."""
    return Path(sweep) / ERRORS / f"{run_id}.log"


def run_task(spec: RunSpec, sweep: str) -> dict[str, Any]:
    """Run ``spec`` into ``sweep``/runs/<run_id>; a result record (never raises for a run
    that fails: its traceback is written to ``sweep``/errors/<run_id>.log)."""
    started = time.perf_counter()
    try:
        with in_flight(Path(sweep), spec.run_id):
            simulate(spec, Path(sweep))
    except Exception as exc:
        status = LOST if isinstance(exc, OUTSIDE) else FAILED
        log = write_log(spec, Path(sweep), exc)
        message = " ".join(str(exc).split())[:300] or type(exc).__name__
        return result(spec, status, started, f"{type(exc).__name__}: {message}", log)
    return result(spec, DONE, started)


def write_log(spec: RunSpec, sweep: Path, exc: Exception) -> str | None:
    """Write the traceback of a failed run; its path (None if it cannot be written: the
    disk may be full)."""
    log = error_log(sweep, spec.run_id)
    text = f"run {spec.run_id} ({spec.label}, seed {spec.seed}) failed:\n"
    with contextlib.suppress(OSError, WriteError):
        log.parent.mkdir(parents=True, exist_ok=True)
        write_text_atomic(log, text + "".join(traceback.format_exception(exc)))
        return str(log)
    return None


def simulate(spec: RunSpec, sweep: Path) -> None:
    """Build and run ``spec``'s simulation into its run folder."""
    scenario = spec.load()
    if spec.video is not None:
        Path(spec.video).parent.mkdir(parents=True, exist_ok=True)
        render = scenario.render.model_copy(update={"video": spec.video})
        scenario = scenario.model_copy(update={"render": render})
    sim = Simulation(scenario)
    run_session(sim, run_folder(sweep, spec.run_id), overwrite=True, stop=StopRequest(False))


def result(
    spec: RunSpec, status: str, started: float, error: str | None = None, log: str | None = None
) -> dict[str, Any]:
    """The record a worker sends back to the sweep."""
    elapsed = round(time.perf_counter() - started, 3)
    return {
        "run_id": spec.run_id,
        "status": status,
        "run_time_s": elapsed,
        "error": error,
        "log": log,
    }
