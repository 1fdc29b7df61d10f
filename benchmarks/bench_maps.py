"""Phase 1 (geometry) benchmark: grid -> wall segments -> pymunk Space -> 181-ray scans.

Run ``python benchmarks/bench_maps.py`` from the repository root. It prints medians over
7 repeats for :func:`mresim_phys.world.maps.wall_segments` on ``maps/office.png`` and on a
synthetic 2000 x 2000 maze, the time to build a pymunk Space from the segments (added in
a shuffled order with a fixed seed), and the cost of a 181-ray scan through the low-level
``cpSpaceSegmentQueryFirst`` on three spatial indexes: the BB tree with segments added in
generation order, the BB tree with shuffled insertion, and ``use_spatial_hash(10, 10 n)``;
then the same scan on the shuffled BB tree through pymunk's own ``segment_query_first``
(which allocates its result per ray). This is a script, not a test; the figures it gave
are in ``docs/performance.md`` (Kernels).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import cv2
import numpy as np
import pymunk
from numpy.typing import NDArray
from pymunk._chipmunk_cffi import ffi, lib

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from mresim_phys.scenario.readers import load_map  # noqa: E402
from mresim_phys.world.maps import wall_segments  # noqa: E402

REPEATS = 7
N_POSES = 200
N_RAYS = 181


def median_seconds(fn: Callable[[], object], repeats: int = REPEATS) -> float:
    """Median wall-clock time of ``fn()`` over ``repeats`` runs."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def _maze_passages(cells: int, rng: np.random.Generator) -> list[tuple[int, int, int, int]]:
    """Randomised depth-first spanning tree of a ``cells x cells`` lattice, plus 12% loops."""
    seen = np.zeros((cells, cells), dtype=bool)
    stack, links = [(0, 0)], []
    seen[0, 0] = True
    while stack:
        r, c = stack[-1]
        options = [
            (r + dr, c + dc)
            for dr, dc in ((0, 1), (1, 0), (0, -1), (-1, 0))
            if 0 <= r + dr < cells and 0 <= c + dc < cells and not seen[r + dr, c + dc]
        ]
        if not options:
            stack.pop()
            continue
        nr, nc = options[rng.integers(len(options))]
        seen[nr, nc] = True
        links.append((r, c, nr, nc))
        stack.append((nr, nc))
    extra = rng.integers(0, cells - 1, size=(int(0.12 * cells * cells), 2))
    links += [(r, c, r, c + 1) for r, c in extra[: len(extra) // 2]]
    links += [(r, c, r + 1, c) for r, c in extra[len(extra) // 2 :]]
    return links


def synthetic_maze(size: int = 2000, pitch: int = 40, wall: int = 4, seed: int = 7) -> NDArray:
    """A big2000-like maze: 40-cell pitch, 4-cell walls, 300 discs and 120 diagonal bars."""
    rng = np.random.default_rng(seed)
    cells = size // pitch
    img = np.zeros((size, size), dtype=np.uint8)
    for k in range(cells + 1):  # full lattice of walls
        img[k * pitch : k * pitch + wall, :] = 1
        img[:, k * pitch : k * pitch + wall] = 1
    door = slice(wall + 8, pitch - 8)
    for r, c, nr, nc in _maze_passages(cells, rng):
        y, x = min(r, nr) * pitch, min(c, nc) * pitch
        if nr != r:  # open the wall below cell (r, c)
            img[y + pitch : y + pitch + wall, x:][:, door] = 0
        else:
            img[y:, x + pitch : x + pitch + wall][door, :] = 0
    centres, radii = rng.integers(0, size, (300, 2)), rng.integers(3, 9, 300)
    for (x, y), radius in zip(centres, radii, strict=True):
        cv2.circle(img, (int(x), int(y)), int(radius), 1, thickness=-1)
    starts = rng.integers(40, size - 40, (120, 2))
    for (x, y), (dx, dy) in zip(starts, rng.integers(-40, 41, (120, 2)), strict=True):
        cv2.line(img, (int(x), int(y)), (int(x + dx), int(y + dy)), 1, thickness=2)
    return img.astype(bool)


def build_space(segments: NDArray[np.float64], order: NDArray[np.intp]) -> pymunk.Space:
    """A Space with one static Segment per row of ``segments``, added in ``order``."""
    space = pymunk.Space()
    body = space.static_body
    shapes = [pymunk.Segment(body, (s[0], s[1]), (s[2], s[3]), 0) for s in segments[order]]
    space.add(*shapes)
    return space


def scan_poses(occupied: NDArray[np.bool_], rng: np.random.Generator) -> NDArray[np.float64]:
    """``(N_POSES, 3)`` random poses (x, y, heading) at centres of free cells."""
    free = np.argwhere(~occupied)
    picks = free[rng.choice(len(free), N_POSES, replace=False)]
    headings = rng.integers(0, 360, N_POSES) * np.pi / 180
    return np.column_stack((picks[:, 1] + 0.5, picks[:, 0] + 0.5, headings))


def scan_rays(
    poses: NDArray[np.float64], max_range: float
) -> Iterator[tuple[tuple[float, float], list[list[float]]]]:
    """Each pose's origin and the ends of its 181-ray, 180-degree scan."""
    offsets = np.linspace(-np.pi / 2, np.pi / 2, N_RAYS)
    for x, y, heading in poses:
        angles = heading + offsets
        ends = np.column_stack((x + max_range * np.cos(angles), y + max_range * np.sin(angles)))
        yield (x, y), ends.tolist()


def scan_all(space: pymunk.Space, poses: NDArray[np.float64], max_range: float) -> float:
    """Cast a 181-ray, 180-degree scan from every pose; return the sum of hit distances."""
    query, cp_space = lib.cpSpaceSegmentQueryFirst, space._space
    info, shape_filter, null = ffi.new("cpSegmentQueryInfo *"), pymunk.ShapeFilter(), ffi.NULL
    total = 0.0
    for start, ends in scan_rays(poses, max_range):
        for end in ends:
            hit = query(cp_space, start, end, 0.0, shape_filter, info)
            total += info.alpha * max_range if hit != null else max_range
    return total


def scan_all_wrapper(space: pymunk.Space, poses: NDArray[np.float64], max_range: float) -> float:
    """:func:`scan_all` through pymunk's ``Space.segment_query_first`` instead of the C call."""
    shape_filter = pymunk.ShapeFilter()
    total = 0.0
    for start, ends in scan_rays(poses, max_range):
        for end in ends:
            hit = space.segment_query_first(start, end, 0.0, shape_filter)
            total += hit.alpha * max_range if hit is not None else max_range
    return total


def bench_map(name: str, occupied: NDArray[np.bool_], max_range: float) -> dict[str, object]:
    """All figures for one map."""
    segments = wall_segments(occupied)
    n = len(segments)
    rng = np.random.default_rng(0)
    shuffled = rng.permutation(n)
    row: dict[str, object] = {"map": name, "cells": f"{occupied.shape[1]}x{occupied.shape[0]}"}
    row["segs"] = n
    row["segments ms"] = 1e3 * median_seconds(lambda: wall_segments(occupied))
    row["build ms"] = 1e3 * median_seconds(lambda: build_space(segments, shuffled))
    poses = scan_poses(occupied, rng)
    spaces = {
        "sorted": build_space(segments, np.arange(n)),
        "shuffled": build_space(segments, shuffled),
        "hash10": build_space(segments, shuffled),
    }
    spaces["hash10"].use_spatial_hash(10, 10 * n)
    sums = {key: scan_all(space, poses, max_range) for key, space in spaces.items()}
    assert np.allclose(list(sums.values()), sums["sorted"]), f"indexes disagree: {sums}"
    for key, space in spaces.items():
        seconds = median_seconds(lambda space=space: scan_all(space, poses, max_range))
        row[f"scan us {key}"] = 1e6 * seconds / N_POSES
    shuffled_space = spaces["shuffled"]
    assert np.isclose(scan_all_wrapper(shuffled_space, poses, max_range), sums["sorted"])
    seconds = median_seconds(lambda: scan_all_wrapper(shuffled_space, poses, max_range))
    row["scan us wrapper"] = 1e6 * seconds / N_POSES
    return row


def print_table(rows: list[dict[str, object]]) -> None:
    """Print rows as an aligned text table."""
    keys = list(rows[0])
    cells = [[f"{r[k]:.1f}" if isinstance(r[k], float) else str(r[k]) for k in keys] for r in rows]
    widths = [max(len(k), *(len(c[i]) for c in cells)) for i, k in enumerate(keys)]
    print("  ".join(k.rjust(w) for k, w in zip(keys, widths, strict=True)))
    for c in cells:
        print("  ".join(v.rjust(w) for v, w in zip(c, widths, strict=True)))


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark and print the table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--range", type=float, default=300.0, help="scan range in cells")
    args = parser.parse_args(argv)
    cv2.setNumThreads(1)
    office = load_map(ROOT / "maps" / "office.png").occupied
    rows = [
        bench_map("office.png", office, args.range),
        bench_map("maze2000", synthetic_maze(), args.range),
    ]
    print(
        f"medians of {REPEATS}; scans: {N_RAYS} rays over 180 deg, range {args.range:g} cells, "
        f"{N_POSES} free poses, low-level cpSpaceSegmentQueryFirst "
        "('wrapper': pymunk's segment_query_first, shuffled BB tree)"
    )
    print_table(rows)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
