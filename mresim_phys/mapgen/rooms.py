"""Procedural maps (phase 0, input data): buildings and offices as free rectangles with doors.

A plan is a list of free rectangles (rooms, corridors) carved out of solid rock, separated
by walls ``wall`` cells thick. Two rectangles are neighbours when a wall of exactly that
thickness separates them over at least a door and a cell either side; a door is carved
through the wall between some neighbours: a random spanning tree of the neighbour graph
(so every room can be reached), preferring the corridors, then each other neighbour pair
with the chance ``loops``. Every draw comes from the stream given, so a seed gives one map.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mresim_phys.mapgen.params import BuildingParams, OfficeParams
from mresim_phys.types import BoolGrid


@dataclass(frozen=True)
class Rect:
    """A free rectangle: columns x0..x1, rows y0..y1 (half-open); a corridor or a room."""

    x0: int
    y0: int
    x1: int
    y1: int
    corridor: bool = False


@dataclass(frozen=True)
class Wall:
    """The wall between two rectangles: across rows (``vertical``) or columns, at ``at``
    (its first cell), ``thick`` cells thick, shared over ``lo``..``hi`` along it."""

    a: int
    b: int
    vertical: bool
    at: int
    thick: int
    lo: int
    hi: int


def building(p: BuildingParams, width: int, height: int, rng: np.random.Generator) -> BoolGrid:
    """A building: a corridor across its longer side (unless ``corridor`` is 0) and rooms
    split off the rest until no side exceeds ``room_max``."""
    w, inner = p.wall, Rect(p.wall, p.wall, width - p.wall, height - p.wall)
    halves = [inner]
    rects: list[Rect] = []
    if p.corridor > 0:
        along_x = inner.x1 - inner.x0 >= inner.y1 - inner.y0
        lo = (inner.y0 if along_x else inner.x0) + p.room_min + w
        hi = (inner.y1 if along_x else inner.x1) - p.room_min - w - p.corridor
        at = int(rng.integers(lo, hi + 1))
        if along_x:
            rects.append(Rect(inner.x0, at, inner.x1, at + p.corridor, corridor=True))
            halves = [
                replace_y(inner, inner.y0, at - w),
                replace_y(inner, at + p.corridor + w, inner.y1),
            ]
        else:
            rects.append(Rect(at, inner.y0, at + p.corridor, inner.y1, corridor=True))
            halves = [
                replace_x(inner, inner.x0, at - w),
                replace_x(inner, at + p.corridor + w, inner.x1),
            ]
    for half in halves:
        rects += split(half, p.room_min, p.room_max, w, rng)
    return carve(rects, width, height, p.door, p.loops, w, rng)


def office(p: OfficeParams, width: int, height: int, rng: np.random.Generator) -> BoolGrid:
    """An office floor: a corridor along its length, ``cross`` corridors across it, and a
    row of offices between them on each side, each with a door to the corridor."""
    w = p.wall
    mid = (height - p.corridor) // 2 + int(rng.integers(-2, 3))
    corridor = Rect(w, mid, width - w, mid + p.corridor, corridor=True)
    rects = [corridor]
    span = width - 2 * w
    crosses = [w + (k + 1) * span // (p.cross + 1) - p.corridor // 2 for k in range(p.cross)]
    rects += [Rect(x, w, x + p.corridor, height - w, corridor=True) for x in crosses]
    edges = [w, *[x for c in crosses for x in (c - w, c + p.corridor + w)], width - w]
    for x0, x1 in zip(edges[::2], edges[1::2], strict=True):
        for y0, y1 in ((w, mid - w), (mid + p.corridor + w, height - w)):
            rects += row_of_offices(x0, x1, y0, y1, p, rng)
    return carve(rects, width, height, p.door, 0.0, w, rng, every_room_to_corridor=True)


def row_of_offices(
    x0: int, x1: int, y0: int, y1: int, p: OfficeParams, rng: np.random.Generator
) -> list[Rect]:
    """Offices of random widths side by side filling columns x0..x1 (the last one takes the
    rest, or the row is one office if it is too narrow for two)."""
    out, x = [], x0
    while x1 - x >= 2 * p.office_min + p.wall:
        width = int(rng.integers(p.office_min, p.office_max + 1))
        if x1 - (x + width + p.wall) < p.office_min:
            break
        out.append(Rect(x, y0, x + width, y1))
        x += width + p.wall
    out.append(Rect(x, y0, x1, y1))
    return out


def replace_x(r: Rect, x0: int, x1: int) -> Rect:
    return Rect(x0, r.y0, x1, r.y1, r.corridor)


def replace_y(r: Rect, y0: int, y1: int) -> Rect:
    return Rect(r.x0, y0, r.x1, y1, r.corridor)


def split(r: Rect, room_min: int, room_max: int, wall: int, rng: np.random.Generator) -> list[Rect]:
    """``r`` split by walls until no side exceeds ``room_max`` (each part at least
    ``room_min``), the longer side first."""
    width, height = r.x1 - r.x0, r.y1 - r.y0
    if max(width, height) <= room_max or max(width, height) < 2 * room_min + wall:
        return [r]
    if width >= height:
        at = int(rng.integers(r.x0 + room_min, r.x1 - room_min - wall + 1))
        parts = [replace_x(r, r.x0, at), replace_x(r, at + wall, r.x1)]
    else:
        at = int(rng.integers(r.y0 + room_min, r.y1 - room_min - wall + 1))
        parts = [replace_y(r, r.y0, at), replace_y(r, at + wall, r.y1)]
    return [room for part in parts for room in split(part, room_min, room_max, wall, rng)]


def walls_between(rects: list[Rect], door: int, wall: int) -> list[Wall]:
    """Every pair of rectangles one wall apart, sharing enough of it for a door (found by
    the side each starts on, not by trying every pair)."""
    starts_x: dict[int, list[int]] = {}
    starts_y: dict[int, list[int]] = {}
    for k, r in enumerate(rects):
        starts_x.setdefault(r.x0, []).append(k)
        starts_y.setdefault(r.y0, []).append(k)
    out = []
    for i, a in enumerate(rects):
        for j in starts_x.get(a.x1 + wall, []):  # b to the right of a
            b = rects[j]
            lo, hi = max(a.y0, b.y0), min(a.y1, b.y1)
            if hi - lo >= door + 2:
                out.append(Wall(i, j, True, a.x1, wall, lo, hi))
        for j in starts_y.get(a.y1 + wall, []):  # b below a
            b = rects[j]
            lo, hi = max(a.x0, b.x0), min(a.x1, b.x1)
            if hi - lo >= door + 2:
                out.append(Wall(i, j, False, a.y1, wall, lo, hi))
    return out


def carve(
    rects: list[Rect], width: int, height: int, door: int, loops: float, wall: int,
    rng: np.random.Generator, every_room_to_corridor: bool = False,
) -> BoolGrid:  # fmt: skip
    """The occupancy grid of ``rects`` with doors (module docstring); with
    ``every_room_to_corridor`` every room beside a corridor gets a door to it too."""
    occupied = np.ones((height, width), dtype=bool)
    for r in rects:
        occupied[r.y0 : r.y1, r.x0 : r.x1] = False
    walls = walls_between(rects, door, wall)
    weights = rng.random(len(walls))
    for k, found in enumerate(walls):  # corridors first: rooms open onto them
        if rects[found.a].corridor or rects[found.b].corridor:
            weights[k] *= 0.25
    parent = list(range(len(rects)))
    chosen = []
    for k in np.argsort(weights, kind="stable").tolist():
        found = walls[k]
        ra, rb = root(parent, found.a), root(parent, found.b)
        to_corridor = every_room_to_corridor and (
            rects[found.a].corridor or rects[found.b].corridor
        )
        if ra != rb:
            parent[ra] = rb
            chosen.append(found)
        elif to_corridor or rng.random() < loops:
            chosen.append(found)
    for found in chosen:
        at = int(rng.integers(found.lo + 1, found.hi - door))
        if found.vertical:
            occupied[at : at + door, found.at : found.at + found.thick] = False
        else:
            occupied[found.at : found.at + found.thick, at : at + door] = False
    return occupied


def root(parent: list[int], i: int) -> int:
    """Union-find: the root of ``i`` (path halving)."""
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i
