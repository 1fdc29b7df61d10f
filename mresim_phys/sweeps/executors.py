"""Sweep executors (sweeps, running): a local process pool or a Dask distributed cluster.

Both run the same task (``sweeps/worker.run_task``) on the same plain run data, so they
give the same runs; only the wall times differ. A backend keeps at most ``slots`` runs in
flight (one per worker process or Dask worker thread), so "active" means running, and a
killed sweep loses at most the runs that were running. A run whose worker died (a killed
process: ``BrokenProcessPool``; a Dask worker or connection lost) is recorded ``lost``
(run again on resume) and the sweep goes on: a broken process pool is replaced by a new
one, a Dask client that lost its scheduler stops the sweep (:class:`BackendLost`).

* :class:`LocalPool`: ``concurrent.futures.ProcessPoolExecutor`` whose workers fork from
  a *forkserver* that imported mresim once (never from the busy parent: no forked copies
  of its threads, numba's thread pool or open files), or *spawn* where there is no
  forkserver (Windows). Workers die with the sweep, even when it is SIGKILLed
  (``sweeps/lifeline.worker_init``).
* :class:`DaskPool`: ``--dask local:N`` starts a ``LocalCluster`` of N one-thread worker
  processes; ``--dask tcp://host:8786`` joins a running scheduler (its workers need
  mresim_phys installed and the scenario and map paths readable, and write to the same
  sweep folder: a shared file system). An address where no Dask scheduler answers within
  ``sweeps/dask_connect.CONNECT_TIMEOUT`` seconds is a user error.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import importlib
import multiprocessing
import os
import time
from collections.abc import Callable, Iterable
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from typing import Any, Protocol

from mresim_phys.errors import MresimError
from mresim_phys.parallel import usable_cores
from mresim_phys.sweeps.dask_connect import connect
from mresim_phys.sweeps.expand import RunSpec
from mresim_phys.sweeps.lifeline import start_time, worker_init
from mresim_phys.sweeps.worker import LOST, run_task

Result = dict[str, Any]
CANCELLED = (concurrent.futures.CancelledError, asyncio.CancelledError)


class BackendLost(MresimError):
    """The backend cannot run more runs (a Dask client that lost its scheduler)."""


class Backend(Protocol):
    """Where runs execute."""

    slots: int
    name: str
    lost_workers: int

    def submit(self, spec: RunSpec, sweep: str) -> Any:
        """Start ``spec``; a future whose ``result()`` is the worker's record."""

    def wait_any(self, futures: list[Any]) -> list[Any]:
        """Block until at least one of ``futures`` is done; the done ones."""

    def recover(self, lost: int) -> None:
        """After ``lost`` runs whose worker died: be ready for more runs (counting the lost
        workers), or raise BackendLost."""

    def close(self) -> None:
        """Stop the workers (or leave the cluster)."""


def worker_context() -> multiprocessing.context.BaseContext:
    """*forkserver* where the system has it (a clean server process imports mresim once,
    with no threads running, and forks each worker from it: numba's compiled kernels and
    pymunk come along without a second import and without forking a busy parent), else
    *spawn*."""
    if "forkserver" not in multiprocessing.get_all_start_methods():
        return multiprocessing.get_context("spawn")
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(["mresim_phys.sweeps.worker"])
    return context


class LocalPool:
    """A pool of ``workers`` processes that die with the sweep."""

    def __init__(self, workers: int) -> None:
        self.slots, self.name = workers, f"{workers} local process{'es' * (workers > 1)}"
        self.lost_workers = 0
        self.pool = self.start()

    def start(self) -> ProcessPoolExecutor:
        """A new process pool whose workers watch this process."""
        me = os.getpid()
        return ProcessPoolExecutor(
            max_workers=self.slots,
            mp_context=worker_context(),
            initializer=worker_init,
            initargs=(me, start_time(me)),
        )

    def submit(self, spec: RunSpec, sweep: str) -> Any:
        """Start ``spec`` in a worker process."""
        return self.pool.submit(run_task, spec, sweep)

    def wait_any(self, futures: list[Any]) -> list[Any]:
        """The futures done once at least one is."""
        return list(wait(futures, return_when=FIRST_COMPLETED).done)

    def recover(self, lost: int) -> None:
        """Replace a broken pool (a worker process died) by a new one."""
        if getattr(self.pool, "_broken", False):  # no public flag
            self.lost_workers += 1
            self.close()
            self.pool = self.start()

    def close(self) -> None:
        """Stop the worker processes: runs not started are cancelled, running ones (only
        after an interruption) are killed; their temporary folders go on the next resume."""
        processes = list(getattr(self.pool, "_processes", {}).values())  # no public handle
        self.pool.shutdown(wait=False, cancel_futures=True)
        for process in processes:
            if process.is_alive():
                process.terminate()
        for process in processes:
            process.join()


class DaskPool:
    """A Dask distributed client: a LocalCluster it started, or a running scheduler."""

    def __init__(self, client: Any, cluster: Any = None, own: bool = True) -> None:
        """Use ``client`` (and close it, and ``cluster``, at the end if ``own``)."""
        self.client, self.cluster, self.own = client, cluster, own
        self.lost_workers = 0
        self.slots = max(1, sum(client.nthreads().values()))
        self.name = f"Dask at {client.scheduler.address} ({self.slots} worker threads)"

    @classmethod
    def at(cls, address: str) -> DaskPool:
        """A pool on ``local:N`` (a LocalCluster of N one-thread worker processes, started
        here) or on the scheduler at ``address``."""
        distributed: Any = importlib.import_module("distributed")  # an untyped library
        if not address.startswith("local:"):
            return cls(connect(distributed.Client, address))
        cluster = distributed.LocalCluster(
            n_workers=local_workers(address),
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
        )
        return cls(distributed.Client(cluster), cluster)

    def submit(self, spec: RunSpec, sweep: str) -> Any:
        """Start ``spec`` on a Dask worker."""
        return self.client.submit(run_task, spec, sweep, pure=False)

    def wait_any(self, futures: list[Any]) -> list[Any]:
        """The futures done once at least one is."""
        distributed: Any = importlib.import_module("distributed")
        return list(distributed.wait(futures, return_when="FIRST_COMPLETED").done)

    def recover(self, lost: int) -> None:
        """Count the lost workers; BackendLost if the client lost its scheduler."""
        self.lost_workers += lost
        deadline = time.monotonic() + 10
        while self.client.status != "running" and time.monotonic() < deadline:
            time.sleep(0.2)  # the client may be reconnecting
        if self.client.status != "running":
            raise BackendLost(
                f"lost the Dask scheduler at {self.client.scheduler.address} (client"
                f" {self.client.status}); the runs finished so far are kept: run the same"
                " command again to resume."
            )

    def close(self) -> None:
        """Leave the scheduler (and stop the LocalCluster this pool started)."""
        if not self.own:
            return
        self.client.close()
        if self.cluster is not None:
            self.cluster.close()


def local_workers(address: str) -> int:
    """N of ``local:N``; MresimError for anything else."""
    text = address.removeprefix("local:")
    if not text.isdigit() or int(text) < 1:
        raise MresimError(
            f"--dask {address!r}: expected local:N with N >= 1 workers (e.g. local:4), or a"
            " scheduler address such as tcp://host:8786."
        )
    return int(text)


def make_backend(workers: int | None, dask: str | None) -> Backend:
    """The backend the command line asks for: Dask if ``dask``, else a local pool."""
    if dask is not None:
        return DaskPool.at(dask)
    return LocalPool(workers or usable_cores())


def execute(
    specs: Iterable[RunSpec],
    sweep: str,
    backend: Backend,
    on_start: Callable[[RunSpec], None],
    on_result: Callable[[RunSpec, Result], None],
) -> None:
    """Run every spec on ``backend``, at most ``backend.slots`` at a time, reporting each
    start and each result (in the order they finish; a run whose worker died is a ``lost``
    record). BackendLost when the backend cannot go on (the runs in flight reported)."""
    waiting = iter(specs)
    active: dict[Any, RunSpec] = {}

    def fill() -> None:
        while len(active) < backend.slots:
            spec = next(waiting, None)
            if spec is None:
                return
            active[backend.submit(spec, sweep)] = spec
            on_start(spec)

    fill()
    while active:
        lost = 0
        for future in backend.wait_any(list(active)):
            spec = active.pop(future)
            record, died = outcome(future, spec)
            lost += died
            on_result(spec, record)
        if lost:
            backend.recover(lost)
        fill()


def outcome(future: Any, spec: RunSpec) -> tuple[Result, bool]:
    """A finished future's record, and whether its worker died (then the record says
    ``lost``; a run that raises is a record of its own: ``worker.run_task``)."""
    try:
        record: Result = future.result()
    except (Exception, *CANCELLED) as exc:
        error = f"worker lost ({type(exc).__name__}: {' '.join(str(exc).split())[:200]})"
        return {
            "run_id": spec.run_id,
            "status": LOST,
            "run_time_s": None,
            "error": error,
            "log": None,
        }, True
    return record, False
