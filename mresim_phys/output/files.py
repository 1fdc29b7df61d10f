"""Files (output edge): every output file appears whole under its name, or not at all.

A writer writes a temporary sibling (``.<stem>.tmp-<pid>-<n><suffix>``: same folder, so the
rename stays on one file system, and same suffix, so OpenCV and matplotlib still pick the
format from the extension), which is flushed to the disk (``fsync``) and then renamed onto
the final name with :func:`os.replace`, atomic on POSIX (:func:`commit_file`). A process
killed mid-write (even by SIGKILL) leaves at most a hidden temporary file, never a
half-written ``summary.json`` or ``metrics.csv``.

A write that fails (a full disk, ``ENOSPC``; a file over the process's size limit,
``EFBIG``; a quota; ...) deletes its temporary file and raises :class:`WriteError`, a
MresimError naming the final file and the cause, so the command line ends with a
one-paragraph message and a non-zero exit status, never with a traceback or a file cut
short. :func:`atomic_path` serves a file written whole by any writer (text, JSON, PNG,
npz, parquet, figures); :class:`PendingFile` a text stream written as a run goes
(``metrics.csv``), renamed only by :meth:`PendingFile.commit`. Writers that report a
failure without its cause (OpenCV) ask :func:`probe_cause`.
"""

from __future__ import annotations

import contextlib
import itertools
import json
import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from mresim_phys.errors import MresimError

_COUNTER = itertools.count()
PROBE_BYTES = 1 << 20  # what probe_cause tries to write: more than a nearly full disk holds
RETRY = "Nothing was left under that name. Free some space there (or write elsewhere) and retry."


class WriteError(MresimError):
    """An output file could not be written; nothing half-written is left under its name.

    ``path`` is the file's final name, ``cause`` what went wrong (``No space left on
    device``), ``note`` what the user can do about it.
    """

    def __init__(self, path: Path, cause: str, note: str = RETRY) -> None:
        self.path, self.cause, self.note = Path(path), cause, note
        super().__init__(f"cannot write {path}: {cause}. {note}")

    def __reduce__(self) -> tuple[type[WriteError], tuple[Path, str, str]]:
        return (type(self), (self.path, self.cause, self.note))

    def moved(self, old: Path, new: Path, note: str) -> WriteError:
        """The same failure told with ``note``, its path under ``new`` if it was under
        ``old`` (a run's temporary folder, ``new`` the folder it was to become)."""
        try:
            path = Path(new) / self.path.relative_to(old)
        except ValueError:
            path = self.path
        return WriteError(path, self.cause, note)


def cause_of(exc: OSError) -> str:
    """What an OSError says went wrong (``No space left on device``)."""
    return exc.strerror or str(exc) or type(exc).__name__


def temp_sibling(path: Path) -> Path:
    """A fresh temporary name beside ``path`` with the same suffix (unique in this process)."""
    path = Path(path)
    return path.with_name(f".{path.stem}.tmp-{os.getpid()}-{next(_COUNTER)}{path.suffix}")


def make_parent(path: Path) -> None:
    """Create the folders ``path`` goes in (WriteError naming ``path`` if that fails)."""
    try:
        Path(path).parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise WriteError(path, f"cannot create its folder ({cause_of(exc)})") from exc


def probe_cause(folder: Path) -> str | None:
    """Why files cannot be written into ``folder`` (a full disk, a file size limit, ...),
    found by writing PROBE_BYTES there and deleting them; None when that works."""
    probe = temp_sibling(Path(folder) / "write-probe")
    try:
        with probe.open("wb") as handle:
            handle.write(bytes(PROBE_BYTES))
            handle.flush()
            os.fsync(handle.fileno())
    except OSError as exc:
        return cause_of(exc)
    finally:
        with contextlib.suppress(OSError):
            probe.unlink(missing_ok=True)
    return None


def fsync_file(path: Path) -> None:
    """Flush ``path``'s data to the disk (whoever wrote it)."""
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def discard_file(path: Path) -> None:
    """Delete a temporary file if it is there (quietly: this runs after a failure)."""
    with contextlib.suppress(OSError):
        Path(path).unlink(missing_ok=True)


def commit_file(tmp: Path, path: Path) -> Path:
    """Flush the finished temporary file ``tmp`` to the disk and rename it onto ``path``.

    Raises:
        WriteError: If ``tmp`` is missing or cannot be flushed or renamed (``tmp`` deleted).
    """
    try:
        fsync_file(tmp)
        os.replace(tmp, path)
    except OSError as exc:
        discard_file(tmp)
        cause = "the writer left no file" if isinstance(exc, FileNotFoundError) else None
        raise WriteError(path, cause or cause_of(exc)) from exc
    return Path(path)


def writes_to(exc: OSError, tmp: Path) -> bool:
    """Whether ``exc`` came from writing ``tmp`` (a write names no file; an open names it),
    not from reading some other file inside the block."""
    return exc.filename is None or Path(exc.filename) == tmp


@contextmanager
def atomic_path(path: Path) -> Iterator[Path]:
    """Yield a temporary sibling of ``path`` to write; when the block ends, commit it onto
    ``path`` (:func:`commit_file`). If the block raises, delete it; an OSError writing it
    becomes a WriteError naming ``path``."""
    path = Path(path)
    tmp = temp_sibling(path)
    try:
        yield tmp
    except OSError as exc:
        discard_file(tmp)
        if not writes_to(exc, tmp):
            raise
        raise WriteError(path, cause_of(exc)) from exc
    except BaseException:
        discard_file(tmp)
        raise
    commit_file(tmp, path)


def write_text_atomic(path: Path, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` through a temporary sibling; return ``path``."""
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(path)


def write_json_atomic(path: Path, data: Any) -> Path:
    """Write ``data`` as indented JSON (and a final newline) to ``path`` atomically."""
    return write_text_atomic(path, json.dumps(data, indent=2) + "\n")


class PendingFile:
    """A UTF-8 text file written bit by bit under a temporary sibling of ``path``, which
    :meth:`commit` renames onto ``path``: nothing is under ``path`` until then.

    A write that fails deletes the temporary file and raises WriteError; so does every
    later write or commit. Writes are buffered (no ``fsync`` before :meth:`commit`).
    """

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        self.partial = temp_sibling(self.path)
        self._failure: WriteError | None = None
        try:
            self._file = self.partial.open("w", newline="", encoding="utf-8")
        except OSError as exc:
            raise WriteError(self.path, cause_of(exc)) from exc

    def write(self, text: str) -> int:
        """Append ``text`` (what ``csv.writer`` calls)."""
        if self._failure is not None:
            raise self._failure
        try:
            return self._file.write(text)
        except OSError as exc:
            raise self._fail(exc) from exc

    def commit(self) -> Path:
        """Close the file and give it its name (idempotent); WriteError if it failed."""
        if self._failure is None and not self._file.closed:
            try:
                self._file.close()
            except OSError as exc:
                raise self._fail(exc) from exc
            try:
                commit_file(self.partial, self.path)
            except WriteError as exc:
                self._failure = exc
        if self._failure is not None:
            raise self._failure
        return self.path

    def discard(self) -> None:
        """Close and delete the temporary file; nothing appears under ``path``."""
        with contextlib.suppress(OSError):
            self._file.close()
        discard_file(self.partial)

    def _fail(self, exc: OSError) -> WriteError:
        self.discard()
        self._failure = WriteError(self.path, cause_of(exc))
        return self._failure
