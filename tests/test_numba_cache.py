"""Compiled kernels loaded from numba's on-disk cache return their arrays to Python.

Numba's cache can lose the boxing environment of a kernel that another cached kernel also
calls; its array result then fails to reach Python ("'descr' is NULL", a SystemError). It
struck a noiseless run (its scans fold inside ``scanfold._cast_and_fold``) followed in the
same process by a noisy one (``fold_scan`` from Python), once the caches were warm. Each
kernel called from Python is now a kernel of its own; this runs both orders in fresh
processes, twice, so the second loads every kernel from the cache.
"""

from __future__ import annotations

import subprocess
import sys

SCRIPT = """
import numpy as np
from mresim_phys.knowledge.mapping import integrate_scan
from mresim_phys.knowledge.scanfold import scan_into_map
from mresim_phys.planning.dial import PausedSearch, _dijkstra
from mresim_phys.planning.grid import Window
from mresim_phys.types import UNKNOWN
from mresim_phys.world.sensing import Laser, scan
from mresim_phys.world.space import World

occupied = np.zeros((40, 50), dtype=bool)
occupied[0] = occupied[-1] = occupied[:, 0] = occupied[:, -1] = True
world = World(occupied, [0.5])
laser = Laser(range=20.0)
belief = np.full(occupied.shape, UNKNOWN, dtype=np.uint8)
safe = np.zeros(occupied.shape, dtype=bool)
filt = world.query_filter(0, False)
assert scan_into_map(world, (20.5, 20.5), 0.0, laser, filt, belief, safe) is not None
update = integrate_scan(belief, safe, scan(world, (22.5, 20.5), 1.0, laser, filt), 0.1)
assert update is not None and update.free.any()
passable = ~occupied
window = Window.around(passable, (1, 39, 1, 49))
dist, pred, _ = _dijkstra(window.pad, window.wp, window.node((5, 5)), np.inf)
search = PausedSearch(passable, (5, 5), (1, 39, 1, 49))
search.run_below(np.inf)
assert (search.dist == dist).all()
print("arrays came back")
"""


def test_kernels_shared_by_cached_kernels_return_their_arrays() -> None:
    for _ in range(2):  # the second process loads every kernel from a warm cache
        done = subprocess.run(
            [sys.executable, "-c", SCRIPT], capture_output=True, text=True, timeout=600
        )
        assert done.returncode == 0, done.stderr[-2000:]
        assert "arrays came back" in done.stdout
