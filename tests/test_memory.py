"""Process set-up: freed large arrays are reused from the heap, without page faults."""

from __future__ import annotations

import ctypes
import mmap
import resource
import sys

import numpy as np
import pytest

from mresim_phys import memory
from mresim_phys.agents import empty_belief
from mresim_phys.comms.ledger import Ledger
from mresim_phys.planning.dial import _dijkstra
from mresim_phys.strategies.giveup import Tried

glibc_only = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's mallopt")


def minor_faults() -> int:
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt


@glibc_only
def test_a_search_window_allocated_again_and_again_faults_no_pages() -> None:
    """What a replan does many times a step: a Dijkstra over a 2 MB window (its arrays
    allocated inside the compiled kernel and freed after). Without the settings each
    call faulted in its ~750 pages afresh."""
    assert memory.keep_freed_memory()
    pad = np.ones(250_000, dtype=np.bool_)
    pad[:600] = pad[-600:] = False
    pad[::500] = pad[499::500] = False  # the blocked border of a 500-wide window
    _dijkstra(pad, 500, 1000, 3.0)  # compiled, and its arrays' pages faulted in once
    before = minor_faults()
    for _ in range(20):
        _dijkstra(pad, 500, 1000, 3.0)
    assert minor_faults() - before < 20 * 10


@pytest.mark.parametrize(
    "env", [{"MRESIM_MALLOC": "default"}, {"MALLOC_TRIM_THRESHOLD_": "1000000"}]
)
def test_the_user_can_keep_mallocs_own_settings(
    monkeypatch: pytest.MonkeyPatch, env: dict[str, str]
) -> None:
    for name, value in env.items():
        monkeypatch.setenv(name, value)
    memory.keep_freed_memory.cache_clear()
    try:
        assert memory.keep_freed_memory() is False
    finally:
        monkeypatch.undo()
        memory.keep_freed_memory.cache_clear()
        memory.keep_freed_memory()


def resident_pages(grid: np.ndarray) -> int:
    """How many of the pages under ``grid`` are in memory (``mincore``)."""
    libc = ctypes.CDLL(None, use_errno=True)
    libc.mincore.argtypes = (ctypes.c_void_p, ctypes.c_size_t, ctypes.c_void_p)
    page = mmap.PAGESIZE
    start = grid.ctypes.data - grid.ctypes.data % page
    pages = -(-(grid.ctypes.data + grid.nbytes - start) // page)
    flags = np.zeros(pages, dtype=np.uint8)
    assert libc.mincore(ctypes.c_void_p(start), pages * page, flags.ctypes.data) == 0
    return int(np.count_nonzero(flags & 1))


def campus_grids(shape: tuple[int, int]) -> list[np.ndarray]:
    """A robot's whole-map grids: belief, safe space, ledger rows, tried frontiers."""
    belief, safe = empty_belief(shape)
    ledger = Ledger(shape, 1)
    tried = Tried.empty(shape)
    return [belief, safe, ledger.stamps[0], ledger.copies[0], ledger.origins[0], tried.set_aside]


@glibc_only
def test_a_robots_whole_map_grids_take_memory_only_where_written() -> None:
    """A robot made after the heap has held freed blocks of its grids' size (as any robot
    made after the world's build, or a frontier tried at step 30, is): its grids take the
    pages it writes, not the whole map. With ``np.zeros`` the heap handed the freed blocks
    back, ``calloc`` cleared them, and every page stayed mapped (1.2 GB of tried-frontier
    grids on the campus at step 30)."""
    assert memory.keep_freed_memory()
    shape = (4000, 4000)
    dirty = [np.ones(shape, dtype=dtype) for dtype in (np.uint8, np.int32, np.uint8, np.bool_)]
    del dirty  # freed into the heap, every page of them written
    huge_page = 512  # a write may map 2 MB at once where transparent huge pages are on
    for grid in campus_grids(shape):
        grid[2000, 17] = 1
        assert resident_pages(grid) <= huge_page < grid.nbytes // mmap.PAGESIZE
        assert grid.sum() == 1 and grid.shape == shape  # (reading maps the zero page)
