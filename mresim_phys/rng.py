"""Seeding: one ``SeedSequence`` from the scenario seed feeds named random streams.

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


def named_stream(seed: int, name: str, index: int = 0) -> np.random.Generator:
    """The generator for stream ``name`` (and agent ``index``) of a run with ``seed``.

    >>> a = named_stream(7, "strategy", 1).integers(1 << 30)
    >>> b = named_stream(7, "strategy", 1).integers(1 << 30)
    >>> bool(a == b)
    True
    """
    sequence = np.random.SeedSequence(entropy=seed, spawn_key=(stream_key(name), index))
    return np.random.Generator(np.random.PCG64(sequence))
