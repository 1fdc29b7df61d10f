"""Planning (phase 4b): the topological maps shared by every planner and strategy.

Maps are content-addressed: ``shared_map`` returns the one build of an identical mask
and spacing, so robots whose maps were merged (or the base station's) reuse one build.
"""

from __future__ import annotations

import hashlib
import threading
from collections import OrderedDict

import numpy as np

from mresim_phys.planning.topobuild import build_map
from mresim_phys.planning.topomap import TopologicalMap
from mresim_phys.types import BoolGrid

CACHE_SIZE = 8  # maps kept by shared_map: a team's distinct maps at one time, roughly


def digest(passable: BoolGrid) -> bytes:
    """A content key for a mask (its shape and bits)."""
    h = hashlib.blake2b(np.packbits(passable).tobytes(), digest_size=16)
    h.update(np.asarray(passable.shape, dtype=np.int64).tobytes())
    return h.digest()


class MapCache:
    """The last few topological maps, keyed by (mask content, spacing)."""

    def __init__(self, capacity: int = CACHE_SIZE) -> None:
        self.capacity = capacity
        self.builds = 0  # how many maps this cache has built (for tests and benchmarks)
        self._maps: OrderedDict[tuple[bytes, int], TopologicalMap] = OrderedDict()
        self._lock = threading.Lock()

    def get(self, passable: BoolGrid, spacing: int) -> TopologicalMap:
        """The map of ``passable``: an earlier identical build, or a new one.

        Safe to call from several threads (robots on ``simulation.threads``): the table is
        read and changed under a lock, the build runs outside it; of two threads building
        the same map at once, the first to finish stores its (identical) build.
        """
        key = (digest(passable), spacing)
        with self._lock:
            found = self._maps.get(key)
            if found is not None:
                self._maps.move_to_end(key)
                return found
        built = build_map(passable, spacing)
        with self._lock:
            self.builds += 1
            found = self._maps.setdefault(key, built)
            self._maps.move_to_end(key)
            while len(self._maps) > self.capacity:
                self._maps.popitem(last=False)
        return found


SHARED = MapCache()  # content-addressed, so any planner may take any entry


def shared_map(passable: BoolGrid, spacing: int) -> TopologicalMap:
    """The topological map of ``passable`` from the process-wide cache."""
    return SHARED.get(passable, spacing)
