"""Seeding (shared): one ``SeedSequence`` from the scenario seed feeds named random streams.

Each stream is derived from the seed and a fixed key (its name, and the agent
index for per-agent streams), never from the order in which streams are asked
for, so adding a noise source or a robot never shifts any other stream and the
same scenario and seed always give the same run.
"""

from __future__ import annotations

import zlib

import numpy as np


def stream_key(name: str) -> int:
    """A stable 32-bit key for a stream name (Python's ``hash`` is salted per process).

    >>> stream_key("sensing") == stream_key("sensing")
    True
    """
    return zlib.crc32(name.encode("utf-8"))


class Streams:
    """Every random stream of one run, derived from one ``SeedSequence`` of the scenario seed.

    A stream is keyed by its name (and an index: the agent's or event's), never by
    the order in which streams are asked for. The composition root makes one
    ``Streams`` per run and hands each consumer the streams it draws from.

    >>> a, b = Streams(3), Streams(3)
    >>> bool(a.get("sensing", 2).integers(1 << 30) == b.get("sensing", 2).integers(1 << 30))
    True
    """

    def __init__(self, seed: int) -> None:
        self.root = np.random.SeedSequence(entropy=seed)

    def get(self, name: str, index: int = 0) -> np.random.Generator:
        """A fresh generator for stream ``name`` (and ``index``); equal calls, equal draws."""
        key = (*self.root.spawn_key, stream_key(name), index)
        sequence = np.random.SeedSequence(entropy=self.root.entropy, spawn_key=key)
        return np.random.Generator(np.random.PCG64(sequence))

    def of_robot(self, name: str, robot: str) -> np.random.Generator:
        """Stream ``name`` of the robot called ``robot``: keyed by the robot's name, so
        listing the team in another order never changes any robot's draws."""
        return self.get(name, stream_key(robot))
