"""Run logs (output edge): how a run log stores the moving obstacles and doors of a run.

A snapshot's ``movables`` (:class:`~mresim_phys.snapshot.MovableSnapshot`) are stored
in two parts. What never changes for a name, once, in ``meta.json``'s ``movables`` list
(:func:`movable_meta`): ``name``, ``kind``, ``shape`` ([rows, cols] of its cells),
``cells`` (flat indices of the True ones) and a door's ``segment``. What changes, in each
step's line as ``moved``: ``[index, row, col, on]`` for every movable whose top-left cell
or state changed since the previous logged step (all of them at the first step; the key
is left out when nothing moved). :class:`MovablesTrack` writes and reads that list.
Logs of format version 2 or older have neither: their snapshots have no movables.
Layout: ``docs/run-log-format.md``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from mresim_phys.snapshot import MovableSnapshot, read_only

Moved = list[list[int]]  # [index, row, col, on] per movable that changed


def movable_meta(movable: MovableSnapshot) -> dict[str, Any]:
    """The JSON object of what never changes for ``movable``."""
    out: dict[str, Any] = {
        "name": movable.name,
        "kind": movable.kind,
        "shape": [int(n) for n in movable.cells.shape],
        "cells": [int(i) for i in np.flatnonzero(movable.cells)],
    }
    if movable.segment is not None:
        out["segment"] = [[float(v) for v in end] for end in movable.segment]
    return out


def read_movable_meta(entry: dict[str, Any]) -> MovableSnapshot:
    """:func:`movable_meta` read back, off the map at (0, 0) until a step places it;
    KeyError, TypeError or ValueError if it is malformed."""
    rows, cols = (int(n) for n in entry["shape"])
    cells = np.zeros(rows * cols, dtype=bool)
    cells[np.asarray(entry["cells"], dtype=np.int64)] = True
    segment = entry.get("segment")
    ends = None
    if segment is not None:
        (x0, y0), (x1, y1) = segment
        ends = ((float(x0), float(y0)), (float(x1), float(y1)))
    kind = str(entry["kind"])
    if kind not in ("obstacle", "door"):
        raise ValueError(f"movable kind {kind!r}")
    cells_grid = read_only(cells.reshape(rows, cols))
    return MovableSnapshot(str(entry["name"]), kind, cells_grid, (0, 0), False, ends)


class MovablesTrack:
    """The movables as last logged: the writer's reference for ``moved``, the reader's state."""

    def __init__(self, movables: Sequence[MovableSnapshot]) -> None:
        self.now = list(movables)
        self._started = False

    @classmethod
    def from_meta(cls, entries: Sequence[dict[str, Any]]) -> MovablesTrack:
        """The reader's track of a log's ``meta.json`` ``movables`` list."""
        return cls([read_movable_meta(e) for e in entries])

    def write(self, movables: Sequence[MovableSnapshot]) -> Moved:
        """The ``moved`` list of a step (all of them at the first step)."""
        if len(movables) != len(self.now):
            raise ValueError(f"{len(movables)} movables logged, {len(self.now)} at step 0")
        moved = []
        for i, (old, new) in enumerate(zip(self.now, movables, strict=True)):
            if not self._started or (old.at, old.on) != (new.at, new.on):
                moved.append([i, int(new.at[0]), int(new.at[1]), int(new.on)])
        self.now, self._started = list(movables), True
        return moved

    def read(self, moved: Moved) -> tuple[MovableSnapshot, ...]:
        """Apply a step's ``moved`` list; every movable as it is now."""
        for i, row, col, on in moved:
            self.now[i] = replace(self.now[i], at=(int(row), int(col)), on=bool(on))
        return tuple(self.now)
