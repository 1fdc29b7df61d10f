"""The ``mresim`` command's first moments (output edge): signals before the heavy imports.

Importing the simulator (numpy, numba, pymunk, scipy, ...) takes seconds. A Ctrl-C or a
SIGTERM in those seconds would print a ``KeyboardInterrupt`` traceback or end the process
silently with -15. Here, before anything heavy is imported, SIGTERM is turned into an
exception, and either signal ends the command with one line on stderr and the shell's
status (130 for SIGINT, 143 for SIGTERM). Once a run starts, ``output.signals`` takes both
signals over for its own clean stop, and gives this handler back afterwards.
"""

from __future__ import annotations

import os
import signal
import sys
from collections.abc import Sequence
from types import FrameType
from typing import NoReturn


class Terminated(BaseException):
    """SIGTERM arrived outside a run's own handling (raised by the handler below)."""


def _terminate(signum: int, frame: FrameType | None) -> None:
    raise Terminated


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``mresim`` console script: :func:`mresim_phys.cli.main`, with
    SIGINT and SIGTERM answered by a line and exit 130 / 143 from the very start."""
    if signal.getsignal(signal.SIGTERM) is signal.SIG_DFL:
        signal.signal(signal.SIGTERM, _terminate)
    if hasattr(signal, "SIGXFSZ"):  # past `ulimit -f`, a write fails with a message (EFBIG)
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # instead of killing with a core dump
    try:
        from mresim_phys.cli import main as cli_main
    except KeyboardInterrupt:
        _leave("interrupted", 128 + signal.SIGINT)
    except Terminated:
        _leave("terminated (SIGTERM)", 128 + signal.SIGTERM)
    try:
        return cli_main(argv)  # which answers KeyboardInterrupt itself once parsing is done
    except KeyboardInterrupt:  # while the command line was parsed: nothing is written yet
        _leave("interrupted", 128 + signal.SIGINT)
    except Terminated:
        print("mresim: terminated (SIGTERM)", file=sys.stderr)
        return 128 + signal.SIGTERM


def _leave(what: str, status: int) -> NoReturn:
    """End the process at once while it is still importing: nothing is written yet, and a
    KeyboardInterrupt raised inside an extension's import leaves the interpreter marked to
    kill itself with SIGINT at exit (status -2 instead of 130), so it must not exit normally."""
    print(f"mresim: {what} while starting", file=sys.stderr, flush=True)
    sys.stdout.flush()
    os._exit(status)


if __name__ == "__main__":
    sys.exit(main())
