"""Sweep executors (sweeps, running): a local process pool or a Dask distributed cluster.

Both run the same task (``sweeps/worker.run_task``) on the same plain run data, so they
give the same runs; only the wall times differ. A backend keeps at most ``slots`` runs in
flight (one per worker process or Dask worker thread), so "active" means running, and a
killed sweep loses at most the runs that were running.

* :class:`LocalPool`: ``concurrent.futures.ProcessPoolExecutor`` whose workers fork from
  a *forkserver* that imported mresim once (never from the busy parent: no forked copies
  of its threads, numba's thread pool or open files), or *spawn* where there is no
  forkserver (Windows).
* :class:`DaskPool`: ``--dask local:N`` starts a ``LocalCluster`` of N one-thread worker
  processes; ``--dask tcp://host:8786`` joins a running scheduler (its workers need
  mresim_phys installed and the scenario and map paths readable, and write to the same
  sweep folder: a shared file system). An address that does not answer within
  :data:`CONNECT_TIMEOUT` seconds is a user error.
"""

from __future__ import annotations

import importlib
import multiprocessing
import os
import signal
from collections.abc import Callable, Iterable
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from typing import Any, Protocol

from mresim_phys.errors import MresimError
from mresim_phys.sweeps.expand import RunSpec
from mresim_phys.sweeps.worker import run_task

CONNECT_TIMEOUT = 3  # seconds to reach a Dask scheduler
Result = dict[str, Any]


class Backend(Protocol):
    """Where runs execute."""

    slots: int
    name: str

    def submit(self, spec: RunSpec, sweep: str) -> Any:
        """Start ``spec``; a future whose ``result()`` is the worker's record."""

    def wait_any(self, futures: list[Any]) -> list[Any]:
        """Block until at least one of ``futures`` is done; the done ones."""

    def close(self) -> None:
        """Stop the workers (or leave the cluster)."""


def default_workers() -> int:
    """Workers by default: the cores this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


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


def ignore_interrupts() -> None:
    """Worker processes ignore Ctrl-C (the sweep stops them), so a run cut short is never
    written as a finished one."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


class LocalPool:
    """A pool of ``workers`` spawned processes."""

    def __init__(self, workers: int) -> None:
        self.slots, self.name = workers, f"{workers} local process{'es' * (workers > 1)}"
        context = worker_context()
        self.pool = ProcessPoolExecutor(
            max_workers=workers, mp_context=context, initializer=ignore_interrupts
        )

    def submit(self, spec: RunSpec, sweep: str) -> Any:
        """Start ``spec`` in a worker process."""
        return self.pool.submit(run_task, spec, sweep)

    def wait_any(self, futures: list[Any]) -> list[Any]:
        """The futures done once at least one is."""
        return list(wait(futures, return_when=FIRST_COMPLETED).done)

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


def connect(client_class: Any, address: str) -> Any:
    """A client of the scheduler at ``address``; MresimError if it does not answer."""
    if "://" not in address:
        raise MresimError(
            f"--dask {address!r}: expected a scheduler address such as tcp://host:8786, or"
            " local:N to start a local cluster of N workers."
        )
    try:
        return client_class(address, timeout=CONNECT_TIMEOUT)
    except (OSError, TimeoutError, ValueError) as exc:
        raise MresimError(
            f"--dask {address}: no Dask scheduler answered within {CONNECT_TIMEOUT} s"
            f" ({type(exc).__name__}: {' '.join(str(exc).split())[:200]}). Start one (`dask"
            " scheduler` and `dask worker ADDRESS` on the machines), check the host and port,"
            " or use --dask local:N or --workers N to run on this machine."
        ) from None


def make_backend(workers: int | None, dask: str | None) -> Backend:
    """The backend the command line asks for: Dask if ``dask``, else a local pool."""
    if dask is not None:
        return DaskPool.at(dask)
    return LocalPool(workers or default_workers())


def execute(
    specs: Iterable[RunSpec],
    sweep: str,
    backend: Backend,
    on_start: Callable[[RunSpec], None],
    on_result: Callable[[RunSpec, Result], None],
) -> None:
    """Run every spec on ``backend``, at most ``backend.slots`` at a time, reporting each
    start and each result (in the order they finish)."""
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
        for future in backend.wait_any(list(active)):
            spec = active.pop(future)
            on_result(spec, outcome(future, spec))
        fill()


def outcome(future: Any, spec: RunSpec) -> Result:
    """A finished future's record; MresimError if its worker died (a run that raises is a
    record, not an exception: ``worker.run_task``)."""
    try:
        record: Result = future.result()
    except Exception as exc:
        raise MresimError(
            f"the worker running {spec.run_id} ({spec.label}, seed {spec.seed}) died"
            f" ({type(exc).__name__}: {' '.join(str(exc).split())[:200]}), e.g. out of memory."
            " The runs finished so far are kept: run the same command again to resume."
        ) from None
    return record
