"""Process lives (sweeps, running): who owns a sweep folder or a run folder, and is it alive.

A sweep's lock (``sweeps/lock.py``) and each in-flight run's marker
(``sweeps/inflight.py``) record an :class:`Owner`: pid, host and the process's start time
(``/proc/<pid>/stat``, so a pid reused by another process is not mistaken for the owner).
An owner on this host is alive while its pid runs (not a zombie) with the same start time;
an owner on another host (a Dask worker) cannot be asked, so it counts as alive while its
file's heartbeat is fresh.

Pool workers die with their sweep (:func:`worker_init`): a worker asks the kernel to kill
it when its parent (the forkserver) dies (Linux ``PR_SET_PDEATHSIG``), and a watcher thread
kills it within :data:`WATCH_INTERVAL` seconds of the sweep process's death (the
forkserver itself outlives a SIGKILLed sweep while any worker holds its pipe).
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import signal
import socket
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

WATCH_INTERVAL = 0.25  # seconds between a worker's checks that its sweep lives
PR_SET_PDEATHSIG = 1


def this_host() -> str:
    """The name of this machine."""
    return socket.gethostname()


def proc_stat(pid: int) -> list[str] | None:
    """The fields of ``/proc/<pid>/stat`` after the command name, or None (no such process,
    or no /proc)."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text(encoding="ascii", errors="replace")
    except OSError:
        return None
    return text.rsplit(")", 1)[-1].split()


def start_time(pid: int) -> int | None:
    """When ``pid`` started (clock ticks since boot), or None where it cannot be read."""
    fields = proc_stat(pid)
    return int(fields[19]) if fields and len(fields) > 19 and fields[19].isdigit() else None


def pid_alive(pid: int, started: int | None = None) -> bool:
    """Whether process ``pid`` of this host runs (a zombie does not), and started at
    ``started`` when given (and readable)."""
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        pass  # someone else's process: it exists
    except OSError:
        return False
    fields = proc_stat(pid)
    if fields is None:
        return not Path("/proc/self/stat").exists()  # no /proc: trust kill(0)
    if fields[0] in ("Z", "X"):
        return False
    return started is None or start_time(pid) in (None, started)


@dataclass(frozen=True)
class Owner:
    """A process that holds a sweep folder or writes a run folder."""

    pid: int
    host: str
    started: int | None = None
    since: float = 0.0  # wall-clock time it took hold

    @classmethod
    def me(cls) -> Owner:
        """This process."""
        pid = os.getpid()
        return cls(pid, this_host(), start_time(pid), time.time())

    @classmethod
    def from_json(cls, data: Any) -> Owner | None:
        """An owner from its JSON record, or None if the record is damaged."""
        if not isinstance(data, dict):
            return None
        pid, host, started, since = (data.get(k) for k in ("pid", "host", "started", "since"))
        if not isinstance(pid, int) or not isinstance(host, str):
            return None
        started = started if isinstance(started, int) else None
        since = float(since) if isinstance(since, (int, float)) else 0.0
        return cls(pid, host, started, since)

    def to_json(self) -> dict[str, Any]:
        """The JSON record of the owner."""
        return {"pid": self.pid, "host": self.host, "started": self.started, "since": self.since}

    def alive(self, heartbeat: float | None = None, stale_after: float = 60.0) -> bool:
        """Whether the owner still runs: on this host, by its pid; elsewhere, while its
        ``heartbeat`` (a file's mtime) is younger than ``stale_after`` seconds."""
        if self.host == this_host():
            return pid_alive(self.pid, self.started)
        return heartbeat is not None and time.time() - heartbeat < stale_after

    def describe(self) -> str:
        """``pid 123 on host h since 12:00:01``."""
        when = time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(self.since))
        return f"pid {self.pid} on host {self.host} since {when}"


def die_with_parent() -> None:
    """Ask Linux to SIGKILL this process when its parent dies (nothing elsewhere)."""
    with contextlib.suppress(OSError, AttributeError):
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0)


def watch(pid: int, started: int | None, interval: float = WATCH_INTERVAL) -> threading.Thread:
    """A daemon thread that ends this process at once when process ``pid`` dies."""

    def loop() -> None:
        while pid_alive(pid, started):
            time.sleep(interval)
        os._exit(1)  # the sweep is gone: nobody will read this run

    thread = threading.Thread(target=loop, name="mresim-lifeline", daemon=True)
    thread.start()
    return thread


def worker_init(sweep_pid: int, sweep_started: int | None) -> None:
    """Initializer of a pool worker: ignore Ctrl-C (the sweep stops its workers, so a run
    cut short is never written as a finished one) and die with the sweep."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    die_with_parent()
    if os.getppid() == 1:  # the parent died before the prctl
        os._exit(1)
    watch(sweep_pid, sweep_started)
