"""Process set-up (before phase 1): freed large arrays stay in the heap for the next step.

A step allocates and frees many arrays of 0.1-3 MB: search windows of the distance fields
(``planning.dial``), C-space crops, frontier masks, exchange buffers. glibc's ``malloc`` gives
a block above its mmap threshold fresh pages from the kernel and unmaps it when freed, and it
returns the heap's free top to the kernel once that passes its trim threshold; its dynamic
threshold does not help blocks allocated by numba kernels. Every such array then costs a page
fault per 4 KiB page it touches: ~1,000 faults a step (library, 8 robots, the original's
settings), ~2,600 with the paused search's whole-box windows, and 10-15 % of a step.

:func:`keep_freed_memory` raises both thresholds (``mallopt``), so those blocks come from
the heap and go back to it: ~25 faults a step. The process keeps up to
``TRIM_THRESHOLD`` of freed memory instead of returning it. Nothing a run computes depends
on it. It is applied once per process, on Linux with glibc only, and not when the user
set glibc's own ``MALLOC_MMAP_THRESHOLD_`` / ``MALLOC_TRIM_THRESHOLD_`` or
``MRESIM_MALLOC=default``.

With those thresholds a freed 16 MB grid stays in the heap, and ``np.zeros`` of the same
size then gets that block back: ``calloc`` must clear it, and every page of it is mapped at
once. A whole-map grid that a robot fills only where it knows something (its belief, its
ledger rows, the frontiers it tried) is made by :func:`sparse_zeros` instead: its own
anonymous mapping, whose pages the kernel maps only when first written and unmaps when the
grid is freed, whatever the heap holds. On the campus (4000 x 4000, 128 robots, 30 steps)
the tried-frontier grids alone had taken 1.2 GB that way.
"""

from __future__ import annotations

import ctypes
import mmap
import os
import sys
from functools import cache
from typing import Any

import numpy as np
from numpy.typing import DTypeLike, NDArray

M_TRIM_THRESHOLD = -1  # glibc's mallopt parameter numbers (malloc.h)
M_MMAP_THRESHOLD = -3
MMAP_THRESHOLD = 32 * 1024 * 1024  # the largest glibc accepts on 64-bit systems
TRIM_THRESHOLD = 256 * 1024 * 1024
USER_SETTINGS = ("MALLOC_MMAP_THRESHOLD_", "MALLOC_TRIM_THRESHOLD_")
SPARSE_BYTES = 1 << 20  # grids from this size on get their own mapping (sparse_zeros)


@cache
def keep_freed_memory() -> bool:
    """Raise glibc's mmap and trim thresholds once per process; whether they were set."""
    if not sys.platform.startswith("linux") or os.environ.get("MRESIM_MALLOC") == "default":
        return False
    if any(name in os.environ for name in USER_SETTINGS):
        return False  # the user tuned malloc: keep theirs
    try:
        libc = ctypes.CDLL(None)  # the C library this process runs on
        libc.gnu_get_libc_version  # noqa: B018 - glibc only: others number the parameters apart
        mallopt = libc.mallopt
    except (OSError, AttributeError):
        return False
    mallopt.argtypes, mallopt.restype = (ctypes.c_int, ctypes.c_int), ctypes.c_int
    mmap_set: bool = mallopt(M_MMAP_THRESHOLD, MMAP_THRESHOLD) == 1
    trim_set: bool = mallopt(M_TRIM_THRESHOLD, TRIM_THRESHOLD) == 1
    return mmap_set and trim_set


def sparse_zeros(shape: tuple[int, ...], dtype: DTypeLike) -> NDArray[Any]:
    """A zero array of ``shape`` whose memory is taken page by page as it is written: an
    anonymous mapping of its own from :data:`SPARSE_BYTES` on (``np.zeros`` below)."""
    dtype = np.dtype(dtype)
    size = int(np.prod(shape, dtype=np.int64)) * dtype.itemsize
    if size < SPARSE_BYTES:
        return np.zeros(shape, dtype=dtype)
    return np.frombuffer(mmap.mmap(-1, size), dtype=dtype).reshape(shape)
