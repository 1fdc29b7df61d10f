"""Files (output edge): every output file appears whole under its name, or not at all.

A writer writes a temporary sibling (``.<stem>.tmp-<pid>-<n><suffix>``: same folder, so the
rename stays on one file system, and same suffix, so OpenCV and matplotlib still pick the
format from the extension), then renames it onto the final name with :func:`os.replace`,
which is atomic on POSIX. A process killed mid-write (even by SIGKILL) leaves at most a
hidden temporary file, never a half-written ``summary.json`` or ``metrics.csv``.
"""

from __future__ import annotations

import itertools
import json
import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

_COUNTER = itertools.count()


def temp_sibling(path: Path) -> Path:
    """A fresh temporary name beside ``path`` with the same suffix (unique in this process)."""
    path = Path(path)
    return path.with_name(f".{path.stem}.tmp-{os.getpid()}-{next(_COUNTER)}{path.suffix}")


@contextmanager
def atomic_path(path: Path) -> Iterator[Path]:
    """Yield a temporary sibling of ``path`` to write; rename it onto ``path`` on success,
    delete it if the block raises."""
    tmp = temp_sibling(path)
    try:
        yield tmp
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    os.replace(tmp, path)


def write_text_atomic(path: Path, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` through a temporary sibling; return ``path``."""
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(path)


def write_json_atomic(path: Path, data: Any) -> Path:
    """Write ``data`` as indented JSON (and a final newline) to ``path`` atomically."""
    return write_text_atomic(path, json.dumps(data, indent=2) + "\n")
