"""Sweep folder lock (sweeps, running): one ``mresim sweep`` writes a sweep folder at a time.

The lock is ``<sweep>/sweep.lock``, holding its owner's pid, host and start
(``sweeps/lifeline.Owner``). It is taken with ``flock`` (exclusive, non-blocking) on the
file, so the kernel lets go of it when its owner dies, even by SIGKILL: a lock file left
by a dead sweep is simply taken over. Where ``flock`` is not available (no ``fcntl``, or a
file system that refuses it) the file is created with ``O_CREAT | O_EXCL``, and a lock
file whose owner is a dead process of this host is replaced (stale-lock recovery). A lock
held by a live sweep (or by a process of another host, which cannot be asked) is refused
with a message naming its owner (exit status 2).
"""

from __future__ import annotations

import contextlib
import json
import os
import time
from pathlib import Path
from types import TracebackType

from mresim_phys.errors import MresimError
from mresim_phys.sweeps.lifeline import Owner, this_host

LOCK_FILE = "sweep.lock"
OWNER_WAIT = 1.0  # seconds a refused sweep waits for the holder's record to name it

try:
    import fcntl
except ImportError:  # not on POSIX
    fcntl = None  # type: ignore[assignment]


class SweepLocked(MresimError):
    """Another sweep writes the folder."""


def read_owner(path: Path) -> Owner | None:
    """The owner a lock file names, or None (no file, or damaged)."""
    try:
        return Owner.from_json(json.loads(path.read_text(encoding="utf-8")))
    except (OSError, ValueError):
        return None


def holder(path: Path) -> Owner | None:
    """The owner of a lock file another process has flocked. It writes its record just
    after it takes the lock, so a record read at once may be missing or a former owner's
    (a flocked file stays when its owner lets go): the record is read again for up to
    :data:`OWNER_WAIT` seconds until it names a live owner (or one of another host)."""
    deadline = time.monotonic() + OWNER_WAIT
    while True:
        owner = read_owner(path)
        named = owner is not None and (owner.host != this_host() or owner.alive())
        if named or time.monotonic() >= deadline:
            return owner
        time.sleep(0.02)


def refusal(folder: Path, owner: Owner | None) -> SweepLocked:
    """The message refusing a folder another sweep holds."""
    who = owner.describe() if owner is not None else "a process whose record is unreadable"
    return SweepLocked(
        f"{folder} is being written by another `mresim sweep` ({who}; lock file"
        f" {folder / LOCK_FILE}). Two sweeps of one folder would run every run twice and"
        " delete each other's runs in flight: wait for it to end (then run the command again"
        " to resume), stop it, or give another --out. If no such sweep runs (a sweep of"
        f" another machine that died), delete {folder / LOCK_FILE}."
    )


class SweepLock:
    """The lock of one sweep folder, held from :meth:`acquire` to :meth:`release`."""

    def __init__(self, folder: Path) -> None:
        self.folder = Path(folder)
        self.path = self.folder / LOCK_FILE
        self.fd: int | None = None
        self.created = False

    def acquire(self) -> SweepLock:
        """Take the lock; SweepLocked if a live sweep holds it."""
        if fcntl is not None:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
            try:
                locked = self.flock(fd)
            except BaseException:
                os.close(fd)
                raise
            if locked:
                self.fd = fd
                data = json.dumps(Owner.me().to_json()).encode()
                os.pwrite(fd, data, 0)
                os.ftruncate(fd, len(data))
                return self
            os.close(fd)
        self.exclusive_create()
        self.created = True
        return self

    def check(self) -> None:
        """SweepLocked if a live sweep holds the lock (a lock file there taken and let go
        again; nothing is created)."""
        if self.path.is_file():
            self.acquire()
            self.release()

    def flock(self, fd: int) -> bool:
        """flock ``fd``; False if this file system cannot; SweepLocked if held."""
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise refusal(self.folder, holder(self.path)) from None
        except OSError:
            return False
        return True

    def exclusive_create(self) -> None:
        """Without flock: create the lock file exclusively, replacing a stale one (its
        owner a dead process of this host) or an empty one."""
        owner = read_owner(self.path)
        if owner is not None and (owner.host != this_host() or owner.alive()):
            raise refusal(self.folder, owner)
        with contextlib.suppress(OSError):
            if owner is not None or self.path.stat().st_size == 0:
                self.path.unlink()
        try:
            fd = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
        except FileExistsError:
            raise refusal(self.folder, read_owner(self.path)) from None
        os.write(fd, json.dumps(Owner.me().to_json()).encode())
        os.close(fd)

    def release(self) -> None:
        """Let go of the lock. A flocked file stays (deleting it would race a new owner:
        the kernel's lock is what counts); an exclusively created one is deleted."""
        if self.fd is not None:
            os.close(self.fd)
            self.fd = None
        elif self.created:
            self.created = False
            owner = read_owner(self.path)
            if owner is not None and owner.pid == os.getpid():
                self.path.unlink(missing_ok=True)

    def __enter__(self) -> SweepLock:
        return self.acquire()

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> None:
        self.release()
