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
import sys
import weakref
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor, wait
from contextlib import contextmanager
from dataclasses import dataclass, field
from functools import partial
from typing import Literal, TypeVar

from mresim_phys.comms.exchange import run_in_turn
from mresim_phys.comms.ledger import Box, union_box
from mresim_phys.knowledge.mapping import Update
from mresim_phys.types import BeliefGrid

T = TypeVar("T")


@dataclass
class Effects:
    """What one robot's task did to shared state, held back until every robot is done: the
    union of its scan windows (the team coverage recounts it) and the time it spent."""

    belief: BeliefGrid | None = None  # the robot's map, once a scan changed it
    window: Box | None = None  # the union of its scan windows (row0, row1, col0, col1)
    seconds: dict[str, float] = field(default_factory=dict)  # phase -> time spent

    def scanned(self, belief: BeliefGrid, update: Update) -> None:
        """A scan changed ``belief`` inside ``update``'s window."""
        h, w = update.free.shape
        self.scanned_box(belief, (update.row0, update.row0 + h, update.col0, update.col0 + w))

    def scanned_box(self, belief: BeliefGrid, window: Box) -> None:
        """Scans changed ``belief`` inside ``window``."""
        self.belief = belief
        self.window = union_box(self.window, window)

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

    The worker threads are started on the first parallel run and end when the pool is
    closed or garbage-collected.
    """

    def __init__(self, threads: int) -> None:
        self.threads = max(1, threads)
        self._executor: ThreadPoolExecutor | None = None

    def run(self, tasks: Sequence[Callable[[], T]], heavy: Sequence[bool] = ()) -> list[T]:
        """Every task's result, in the order of ``tasks``; the first task's error (in that
        order) is raised after all tasks have finished. Interrupted while waiting, it
        cancels the tasks not yet started and waits for the running ones before raising.

        On threads the tasks marked ``heavy`` start first (a robot that will replan), so
        the light ones fill the threads' time at the end instead of one long task
        running alone; the results keep the order of ``tasks``."""
        if self.threads == 1 or len(tasks) <= 1:
            return [task() for task in tasks]
        marks = list(heavy) + [False] * (len(tasks) - len(heavy))
        start = sorted(range(len(tasks)), key=lambda i: not marks[i])  # stable: heavy first
        with short_gil_turns():
            started = {i: self._pool().submit(tasks[i]) for i in start}
            futures = [started[i] for i in range(len(tasks))]
            try:
                wait(futures)
            except BaseException:  # e.g. KeyboardInterrupt: no task may go on after we return
                for future in futures:
                    future.cancel()  # those not started never start
                wait(futures)
                raise
        errors = [f.exception() for f in futures]
        for error in errors:
            if error is not None:
                raise error
        return [f.result() for f in futures]

    def run_in_chunks(self, tasks: Sequence[Callable[[], None]]) -> None:
        """Run many small ``tasks`` (the exchange's transmissions of one tree level), split
        into one run of consecutive tasks per thread: a thread hand-over costs more than a
        small task. Each chunk runs its tasks in their order; the first error is raised."""
        size = max(-(-len(tasks) // self.threads), 1)
        chunks = [tasks[i : i + size] for i in range(0, len(tasks), size)]
        self.run([partial(run_in_turn, chunk) for chunk in chunks])

    def _pool(self) -> ThreadPoolExecutor:
        if self._executor is None:
            executor = ThreadPoolExecutor(self.threads, thread_name_prefix="mresim-robot")
            weakref.finalize(self, executor.shutdown, wait=False)
            self._executor = executor
        return self._executor

    def close(self) -> None:
        """Stop the worker threads (a later run starts new ones)."""
        if self._executor is not None:
            self._executor.shutdown(wait=True)
            self._executor = None
