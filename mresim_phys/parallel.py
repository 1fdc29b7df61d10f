"""Decide and move phases on threads (phases 4-5): one task per robot, results in robot order.

Within these phases a robot reads only its own state, what it heard in the last
communication phase and the world as the step began (bodies are placed after every
robot moved; ``sim.py``), so robots' replans, moves, scans and map updates are
independent and can run side by side. The heavy parts release the GIL: the scan
(``world/raycast.py``), the map update (``knowledge/mapping.py``) and the planning
kernels are numba ``nogil`` functions, and Chipmunk's queries go through cffi (which
``World`` serialises with a lock: a Chipmunk query locks its Space by a counter that
concurrent queries would corrupt).

What a robot's task does to shared state (the team coverage's touched windows, the phase
timers) is held in its :class:`Effects` and applied by the caller in robot order after
every task has finished, so a run gives the same results, byte for byte, whatever the
thread count and the threads' timing (``tests/test_parallel_step.py``). A task also
stamps its robot's changes in the comm ledger (``comms.network.Network.stamp_own``),
which touches only that robot's rows of it.

The communication phase uses the same threads for the map transmissions of one level of
an exchange tree (``comms.exchange.Exchange.share_group``), a run of them per thread
(:meth:`RobotPool.run_in_chunks`).

A strategy or planner plugin run on threads must keep no mutable state shared between
robots, nor scratch arrays shared between calls unless per thread (the built-in ones share
only the topological map cache, which is locked and content-addressed, and keep their search
arrays in ``threading.local``). ``threads: 1`` (the default) runs every task in the calling
thread, in robot order. Only about half of a task's time is GIL-free; while tasks run the
threads hand the GIL over every 0.2 ms (:func:`short_gil_turns`), see docs/performance.md.
"""

from __future__ import annotations

import os
import queue
import sys
import threading
import weakref
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager, suppress
from dataclasses import dataclass, field
from functools import partial
from typing import Generic, Literal, TypeVar, cast

from mresim_phys.agents import Agent
from mresim_phys.comms.exchange import run_in_turn
from mresim_phys.knowledge.known_area import KNOWN_AREA, KnownArea
from mresim_phys.knowledge.mapping import Update
from mresim_phys.planning.grid import Box, union_box
from mresim_phys.types import BeliefGrid

T = TypeVar("T")


@dataclass
class Effects:
    """What one robot's task did to shared state, held back until every robot is done: the
    union of its scan windows (the team coverage recounts it) and the time it spent."""

    belief: BeliefGrid | None = None  # the robot's map, once a scan changed it
    window: Box | None = None  # the union of its scan windows (row0, row1, col0, col1)
    seconds: dict[str, float] = field(default_factory=dict)  # phase -> time spent
    known: KnownArea | None = None  # the robot's known area (its own, grown at once)

    @classmethod
    def of(cls, robot: Agent) -> Effects:
        """The effects of a task of ``robot``, which grow its known area as it scans."""
        return cls(known=KNOWN_AREA.state_of(robot.features))

    def scanned(self, belief: BeliefGrid, update: Update) -> None:
        """A scan changed ``belief`` inside ``update``'s window."""
        h, w = update.free.shape
        self.scanned_box(belief, (update.row0, update.row0 + h, update.col0, update.col0 + w))

    def scanned_box(self, belief: BeliefGrid, window: Box) -> None:
        """Scans changed ``belief`` inside ``window``."""
        self.belief = belief
        self.window = union_box(self.window, window)
        if self.known is not None:
            self.known.grow(window)

    def spend(self, phase: str, seconds: float) -> None:
        """Add ``seconds`` to ``phase``'s timer."""
        self.seconds[phase] = self.seconds.get(phase, 0.0) + seconds

    def apply(self, touch_box: Callable[[BeliefGrid, Box], None], timers: dict[str, float]) -> None:
        """Pass the held-back window on; add the times."""
        if self.belief is not None and self.window is not None:
            touch_box(self.belief, self.window)
        for phase, seconds in self.seconds.items():
            timers[phase] += seconds


def usable_cores() -> int:
    """Cores this process may run on."""
    if hasattr(os, "sched_getaffinity"):
        return max(len(os.sched_getaffinity(0)), 1)
    return max(os.cpu_count() or 1, 1)


def thread_count(setting: int | Literal["auto"], robots: int) -> int:
    """Worker threads for ``robots`` tasks: ``auto`` = one per usable core; never more
    threads than robots, never fewer than one."""
    wanted = usable_cores() if setting == "auto" else int(setting)
    return max(1, min(wanted, robots))


SWITCH_INTERVAL = 0.0002  # seconds: how long a thread may hold the GIL while another waits


@contextmanager
def short_gil_turns() -> Iterator[None]:
    """Let threads take the GIL from each other every ``SWITCH_INTERVAL`` (CPython's default
    is 5 ms) while the robots' tasks run, then restore the interval.

    A task gives the GIL up for each compiled kernel (a scan takes ~25 us) and waits for it
    back while the other thread runs Python; with the default interval it waits up to
    5 ms. Library, 8 robots, 2 threads: median step 17.3 -> 15.1 ms (1 ms) -> 13.9 ms
    (0.2 ms), 3 interleaved rounds; shorter intervals gained nothing more."""
    before = sys.getswitchinterval()
    sys.setswitchinterval(SWITCH_INTERVAL)
    try:
        yield
    finally:
        sys.setswitchinterval(before)


class RobotPool:
    """Runs one task per robot on up to ``threads`` threads; results come back in task order.

    The calling thread runs tasks too, beside ``threads - 1`` worker threads: a run hands
    work to the workers through a queue and takes tasks itself until none is left, then
    waits for the workers' last ones. On this project's 2-core machine waking a worker
    costs ~50 us and waking the caller again as much, so a pool whose caller only waited
    (``ThreadPoolExecutor``) paid ~115 us a run, 5 runs a step at 8 robots (the robots'
    turns, then the exchange's tree levels); with the caller working a run of 2 empty tasks
    costs ~9 us. The workers are started on the first parallel run and end when the pool is
    closed or garbage-collected.
    """

    def __init__(self, threads: int) -> None:
        self.threads = max(1, threads)
        self._jobs: queue.SimpleQueue[Callable[[], None] | None] | None = None
        self._workers: list[threading.Thread] = []

    def run(self, tasks: Sequence[Callable[[], T]], heavy: Sequence[bool] = ()) -> list[T]:
        """Every task's result, in the order of ``tasks``; the first task's error (in that
        order) is raised after all tasks have finished. Interrupted (a ``KeyboardInterrupt``
        in the calling thread), it starts no further task and waits for the workers' running
        ones before raising.

        On threads the tasks marked ``heavy`` start first (a robot that will replan), so
        the light ones fill the threads' time at the end instead of one long task
        running alone; the results keep the order of ``tasks``."""
        if self.threads == 1 or len(tasks) <= 1:
            return [task() for task in tasks]
        marks = list(heavy) + [False] * (len(tasks) - len(heavy))
        order = sorted(range(len(tasks)), key=lambda i: not marks[i])  # stable: heavy first
        batch = _Batch(tasks, order)
        with short_gil_turns():
            jobs = self._queue()
            for _ in range(min(len(self._workers), len(tasks) - 1)):
                jobs.put(batch.work)
            try:
                batch.work()
            finally:
                batch.stop_and_wait()  # an interrupt: no new task starts, running ones end
        return batch.results()

    def run_in_chunks(self, tasks: Sequence[Callable[[], None]]) -> None:
        """Run many small ``tasks`` (the exchange's transmissions of one tree level), split
        into one run of consecutive tasks per thread: a thread hand-over costs more than a
        small task. Each chunk runs its tasks in their order; the first error is raised."""
        size = max(-(-len(tasks) // self.threads), 1)
        chunks = [tasks[i : i + size] for i in range(0, len(tasks), size)]
        self.run([partial(run_in_turn, chunk) for chunk in chunks])

    def _queue(self) -> queue.SimpleQueue[Callable[[], None] | None]:
        """The workers' job queue, starting them on first use."""
        if self._jobs is None:
            jobs: queue.SimpleQueue[Callable[[], None] | None] = queue.SimpleQueue()
            self._workers = [
                threading.Thread(target=_serve, args=(jobs,), name=f"mresim-robot-{k}",
                                 daemon=True)
                for k in range(self.threads - 1)
            ]  # fmt: skip
            for worker in self._workers:
                worker.start()
            weakref.finalize(self, _stop, jobs, len(self._workers))
            self._jobs = jobs
        return self._jobs

    def close(self) -> None:
        """Stop the worker threads (a later run starts new ones)."""
        if self._jobs is not None:
            _stop(self._jobs, len(self._workers))
            for worker in self._workers:
                worker.join()
            self._jobs, self._workers = None, []


def _serve(jobs: queue.SimpleQueue[Callable[[], None] | None]) -> None:
    """A worker: run jobs until the stop mark (None)."""
    while (job := jobs.get()) is not None:
        with suppress(BaseException):  # a batch keeps its tasks' errors; the worker serves on
            job()


def _stop(jobs: queue.SimpleQueue[Callable[[], None] | None], workers: int) -> None:
    """Ask ``workers`` workers of ``jobs`` to stop once their current job is done."""
    for _ in range(workers):
        jobs.put(None)


class _Batch(Generic[T]):
    """The tasks of one :meth:`RobotPool.run`, taken one at a time (in ``order``) by
    whichever thread is free; each outcome kept in its task's slot."""

    def __init__(self, tasks: Sequence[Callable[[], T]], order: list[int]) -> None:
        self.tasks, self.order = tasks, order
        self.outcomes: list[tuple[bool, object]] = [(False, None)] * len(tasks)
        self.lock = threading.Lock()
        self.all_done = threading.Condition(self.lock)
        self.next = 0  # position in ``order`` of the next task to start
        self.running = 0

    def _take(self) -> int:
        """The next task to run, or -1 when none is left to start."""
        with self.lock:
            if self.next >= len(self.order):
                return -1
            self.next += 1
            self.running += 1
            return self.order[self.next - 1]

    def _done(self, index: int, failed: bool, outcome: object) -> None:
        with self.lock:
            self.outcomes[index] = (failed, outcome)
            self.running -= 1
            if self.running == 0 and self.next >= len(self.order):
                self.all_done.notify_all()

    def work(self) -> None:
        """Run tasks until none is left to start. A task's error is kept for
        :meth:`results`; an interrupt (any other ``BaseException``) is kept too, and raised
        here as well: no further task starts in this thread."""
        while (index := self._take()) >= 0:
            try:
                result: object = self.tasks[index]()
            except Exception as error:
                self._done(index, True, error)
                continue
            except BaseException as stop:
                self._done(index, True, stop)
                raise
            self._done(index, False, result)

    def stop_and_wait(self) -> None:
        """Start no further task; return once no task is running."""
        with self.lock:
            self.next = len(self.order)
            while self.running > 0:
                self.all_done.wait()

    def results(self) -> list[T]:
        """The results in task order, or the first error in that order."""
        for failed, outcome in self.outcomes:
            if failed and isinstance(outcome, BaseException):
                raise outcome
        return [cast(T, outcome) for _, outcome in self.outcomes]
