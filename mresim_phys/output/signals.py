"""Signals (output edge): SIGINT and SIGTERM end a run cleanly at the end of a step.

:func:`stop_on_signals` installs, for the duration of a ``with`` block, handlers that only
record the first signal in a :class:`StopRequest` (and, if asked, say so on stderr); they
never raise, so no ``KeyboardInterrupt`` lands inside a numba kernel or half-way through a
step. The run loop (``output.session``) checks the request after every step, closes its
recorders and writes its summary; further signals while it stops are ignored. The previous
handlers come back when the block ends. Handlers can only be installed from the main thread:
elsewhere (a worker thread) the block installs nothing, and a signal the process ignores
(``SIG_IGN``, e.g. SIGINT of a background job) stays ignored.

Only command-line sessions install handlers: ``Simulation.run()`` keeps Python's defaults.
"""

from __future__ import annotations

import contextlib
import os
import signal
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from types import FrameType
from typing import Any

SIGNALS = (signal.SIGINT, signal.SIGTERM)
Handler = Callable[[int, FrameType | None], Any] | int | None  # what signal.getsignal gives


class StopRequest:
    """The first stop signal received (``signum``), or None while the run may go on."""

    def __init__(self, notice: bool = True) -> None:
        """``notice``: write one line to stderr when the first signal arrives."""
        self.signum: int | None = None
        self.notice = notice

    @property
    def requested(self) -> bool:
        """Whether a stop signal arrived."""
        return self.signum is not None

    @property
    def name(self) -> str | None:
        """The signal's name (``SIGINT``, ``SIGTERM``), or None."""
        return None if self.signum is None else signal.Signals(self.signum).name

    @property
    def exit_status(self) -> int:
        """The shell convention for a process ended by the signal: 128 + its number."""
        return 0 if self.signum is None else 128 + self.signum

    def handle(self, signum: int, frame: FrameType | None) -> None:
        """Signal handler: remember the first signal; ignore the rest."""
        if self.signum is not None:
            return
        self.signum = signum
        if self.notice:
            text = f"\nmresim: {self.name}: stopping after this step (further signals ignored)\n"
            with contextlib.suppress(OSError):  # os.write: no buffered stream to re-enter
                os.write(2, text.encode())


@contextmanager
def stop_on_signals(
    stop: StopRequest | None = None, *, linger: bool = False
) -> Iterator[StopRequest]:
    """Route SIGINT and SIGTERM to ``stop`` (a new StopRequest if None) inside the block.

    Afterwards the previous handlers come back; with ``linger`` (a process that exits right
    after the block), if a stop signal arrived, both signals stay ignored instead, so a
    second Ctrl-C cannot kill the process while it exits with 128 + the first signal.
    """
    stop = stop or StopRequest()
    previous: dict[int, Handler] = {}
    if threading.current_thread() is threading.main_thread():
        for signum in SIGNALS:
            old = signal.getsignal(signum)
            if old is not signal.SIG_IGN:
                previous[signum] = old
                signal.signal(signum, stop.handle)
    try:
        yield stop
    finally:
        for number, handler in previous.items():  # None: a handler set from C; use the default
            if linger and stop.requested:
                signal.signal(number, signal.SIG_IGN)
            else:
                signal.signal(number, signal.SIG_DFL if handler is None else handler)
