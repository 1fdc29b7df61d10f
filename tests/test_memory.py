"""Process set-up: freed large arrays are reused from the heap, without page faults."""

from __future__ import annotations

import resource
import sys

import numpy as np
import pytest

from mresim_phys import memory
from mresim_phys.planning.dial import _dijkstra

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
