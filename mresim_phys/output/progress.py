"""Progress (output): the progress bars of runs and sweeps, on a terminal and off it.

On a terminal a bar is tqdm's, redrawn in place. Off a terminal (a log file, a CI job, a
cluster's output file) tqdm's carriage-return redraws would pile up on one line: there
each update is written once, as a whole line, at most every ``LOG_INTERVAL`` seconds and
never twice the same. :func:`first_run_note` says, before a run, when the compiled kernels
are not cached yet (the first run after an install compiles them: docs/performance.md).
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any, TextIO

from tqdm import tqdm

LOG_INTERVAL = 10.0  # seconds between progress lines off a terminal


class LineWriter:
    """A stream for tqdm off a terminal: each redraw one whole line, repeats dropped."""

    def __init__(self, stream: TextIO) -> None:
        self.stream, self.last = stream, ""

    def write(self, text: str) -> None:
        """Write each non-empty part of ``text`` once, as a line."""
        for part in text.replace("\r", "\n").split("\n"):
            line = part.strip()
            if line and line != self.last:
                self.stream.write(line + "\n")
                self.last = line

    def flush(self) -> None:
        """Flush the stream."""
        self.stream.flush()


def progress_bar(**options: Any) -> tqdm[Any]:
    """A tqdm bar on stderr (module docstring); ``options`` are tqdm's."""
    stream = sys.stderr
    if stream.isatty():
        return tqdm(file=stream, **options)
    return tqdm(file=LineWriter(stream), mininterval=LOG_INTERVAL, ascii=True, **options)


def kernel_cache() -> Path:
    """The folder where numba keeps the compiled kernels of one module of this package
    (``world/``): beside the modules when that folder is writable, else numba's user-wide
    cache folder, or under ``NUMBA_CACHE_DIR`` (numba's own choice, asked of a kernel)."""
    from mresim_phys.world.raycast import cast_fan

    return Path(str(cast_fan.stats.cache_path))


def kernels_cached() -> bool:
    """Whether numba's cache holds compiled kernels of this package (its index files)."""
    return any(kernel_cache().glob("*.nbi"))


def first_run_note() -> str | None:
    """What to tell a user whose kernels are not compiled yet (None: they are)."""
    if kernels_cached():
        return None
    return (
        "mresim: compiling the simulator's kernels for this machine (the first run after an"
        " install: about 45 s more on 2 cores; later runs load them from numba's cache;"
        " `mresim warmup` compiles every kernel at once)"
    )
