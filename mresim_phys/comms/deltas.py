"""Map deltas (phase 6, kernels): pick and merge the cells one transmission carries.

Each cell of an agent has a *code* (occupancy value, plus 4 where it is safe
space), the *tick* it last changed and the agent its value came from. A
transmission selects, inside a few boxes, the sender's cells newer than the
pair's last sync and not received from the receiver; the receiver merges them
(``max`` of occupancy, OR of safe space; with 'latest' beliefs the occupancy of the newer
observation) and stamps what changed, naming the sender as the value's origin only when
the merged value is exactly the sender's (a value mixed from both sides, say the
receiver's obstacle with the sender's safe flag, must still travel back to the sender).
One merge kernel serves both kinds of belief, its per-cell rule inlined. ``numba``
kernels visit each box cell once with no temporary grids: the numpy version of
the same steps cost 8-10 ms per 8-robot step on the office map, mostly in
temporaries over the union of every robot's scan windows. Each agent also keeps the
newest tick of every ``TILE`` x ``TILE`` tile of its grid (``tiles``), so a selection
skips the parts of a row whose tiles hold nothing newer than the pair's last sync: a
box is a step's scan window, but what changed in it is a thin band along the frontiers.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from mresim_phys.types import BeliefGrid, BoolGrid, IntArray

TILE = 16  # cells: the side of the tiles whose newest tick a selection checks first


def tile_shape(shape: tuple[int, int]) -> tuple[int, int]:
    """The shape of the tile-tick grid of a grid of ``shape``."""
    return -(-shape[0] // TILE), -(-shape[1] // TILE)


class Cells(NamedTuple):
    """The map part of one transmission: flat cell indices and their codes (the
    occupancy value, plus 4 where the cell is safe space); with 'latest' beliefs also
    the step at which each value was observed."""

    flat: np.ndarray
    codes: np.ndarray
    seen: np.ndarray | None = None


@njit(cache=True, nogil=True)
def _seen_before(boxes: IntArray, k: int, r: int, c: int) -> bool:
    """Whether cell (r, c) lies in one of ``boxes[:k]`` (visited already)."""
    for m in range(k):  # noqa: SIM110 (numba compiles loops, not generators)
        if boxes[m, 0] <= r < boxes[m, 1] and boxes[m, 2] <= c < boxes[m, 3]:
            return True
    return False


@njit(cache=True, nogil=True, inline="always")
def is_news(
    codes: np.ndarray,
    receiver_codes: np.ndarray,
    seen: np.ndarray | None,
    observed: np.ndarray | None,
    r: int,
    c: int,
) -> bool:
    """Whether merging the sender's cell (r, c) would change the receiver's: its code, or
    with 'latest' beliefs its observation step (the rule of :func:`merge_cells`)."""
    old, theirs = receiver_codes[r, c], codes[r, c]
    if seen is None or observed is None:
        return bool(grown_code(old, theirs) != old)
    if seen[r, c] > observed[r, c]:
        return True
    if seen[r, c] < observed[r, c]:
        return bool(grown_code(old, theirs & 4) != old)
    return bool(grown_code(old, theirs) != old)


@njit(cache=True, nogil=True)
def select_cells(
    boxes: IntArray,
    since: int,
    receiver: int,
    stamps: np.ndarray,
    tiles: np.ndarray,
    origins: np.ndarray,
    codes: np.ndarray,
    receiver_codes: np.ndarray,
    only_lacking: bool,
    news: bool = False,
    seen: np.ndarray | None = None,
    observed: np.ndarray | None = None,
) -> tuple[IntArray, np.ndarray]:
    """(flat indices, codes) of the sender's cells newer than ``since`` inside ``boxes``,
    in raster order box by box (the parts of a row in tiles no newer than ``since`` are
    skipped whole).

    Cells whose value came from ``receiver`` are skipped; with ``only_lacking``
    so are cells whose code the receiver already holds; with ``news`` so are cells whose
    merge would change nothing of the receiver's (:func:`is_news`; ``seen`` and
    ``observed`` the sender's and the receiver's observation steps with 'latest' beliefs).
    """
    total = 0
    for k in range(len(boxes)):
        total += (boxes[k, 1] - boxes[k, 0]) * (boxes[k, 3] - boxes[k, 2])
    index = np.empty(total, np.int64)
    values = np.empty(total, np.uint8)
    cols, n = stamps.shape[1], 0
    for k in range(len(boxes)):
        for r in range(boxes[k, 0], boxes[k, 1]):
            for t in range(boxes[k, 2] // TILE, (boxes[k, 3] - 1) // TILE + 1):
                if tiles[r // TILE, t] <= since:
                    continue
                for c in range(max(t * TILE, boxes[k, 2]), min(t * TILE + TILE, boxes[k, 3])):
                    if stamps[r, c] <= since or origins[r, c] == receiver:
                        continue
                    if only_lacking and codes[r, c] == receiver_codes[r, c]:
                        continue
                    if news and not is_news(codes, receiver_codes, seen, observed, r, c):
                        continue
                    if k > 0 and _seen_before(boxes, k, r, c):
                        continue
                    index[n] = r * cols + c
                    values[n] = codes[r, c]
                    n += 1
    return index[:n], values[:n]


@njit(cache=True, nogil=True, inline="always")
def store(
    belief: BeliefGrid,
    safe: BoolGrid,
    codes: np.ndarray,
    stamps: np.ndarray,
    tiles: np.ndarray,
    origins: np.ndarray,
    r: int,
    c: int,
    code: int,
    origin: int,
    tick: int,
) -> None:
    """Write a merged cell code (occupancy, plus 4 for safe space) into the receiver's grids,
    stamped ``tick`` (its tile too) and coming from ``origin`` (-1: its own)."""
    belief[r, c] = code & 3
    safe[r, c] = (code & 4) != 0
    codes[r, c], stamps[r, c], origins[r, c] = code, tick, origin
    tiles[r // TILE, c // TILE] = max(tiles[r // TILE, c // TILE], tick)


@njit(cache=True, nogil=True)
def stamp_changes(
    box: IntArray,
    belief: BeliefGrid,
    safe: BoolGrid,
    codes: np.ndarray,
    stamps: np.ndarray,
    tiles: np.ndarray,
    origins: np.ndarray,
    tick: int,
    log: IntArray | None = None,
) -> tuple[int, int, int, int, int]:
    """Stamp the cells of ``box`` an agent changed itself (and their tiles); return (count,
    r0, r1, c0, c1). With a ``log`` (room for the box's cells) the changed cells' flat
    indices are written into its first ``count`` places."""
    changed, r0, r1, c0, c1 = 0, box[1], box[0], box[3], box[2]
    for r in range(box[0], box[1]):
        for c in range(box[2], box[3]):
            code = belief[r, c] | (np.uint8(4) if safe[r, c] else np.uint8(0))
            if code == codes[r, c]:
                continue
            codes[r, c], stamps[r, c], origins[r, c] = code, tick, -1
            tiles[r // TILE, c // TILE] = max(tiles[r // TILE, c // TILE], tick)
            if log is not None:
                log[changed] = r * belief.shape[1] + c
            changed += 1
            r0, r1, c0, c1 = min(r0, r), max(r1, r + 1), min(c0, c), max(c1, c + 1)
    return changed, r0, r1, c0, c1


@njit(cache=True, nogil=True, inline="always")
def grown_code(old: int, theirs: int) -> int:
    """The merged code with 'grow' beliefs: the larger occupancy, safe space OR-ed."""
    return max(old & 3, theirs & 3) | ((old | theirs) & 4)


@njit(cache=True, nogil=True, inline="always")
def latest_code(old: int, theirs: int, seen: int, observed: np.ndarray, r: int, c: int) -> int:
    """The merged code with 'latest' beliefs: the side observed earlier keeps only its safe
    flag, so the newer observation's occupancy wins (the larger one, the obstacle, at the
    same step). A newer ``seen`` becomes the cell's observation step, even for an equal value."""
    own = observed[r, c]
    if seen > own:
        observed[r, c] = seen
        return grown_code(old & 4, theirs)
    if seen < own:
        return grown_code(old, theirs & 4)
    return grown_code(old, theirs)


@njit(cache=True, nogil=True)
def merge_cells(
    index: IntArray,
    values: np.ndarray,
    seen: np.ndarray | None,
    belief: BeliefGrid,
    safe: BoolGrid,
    observed: np.ndarray | None,
    codes: np.ndarray,
    stamps: np.ndarray,
    tiles: np.ndarray,
    origins: np.ndarray,
    tick: int,
    sender: int,
    log: IntArray | None = None,
) -> tuple[int, int, int, int, int]:
    """Merge received cells (flat ``index``, codes ``values``); return (cells changed, r0, r1,
    c0, c1 of the changed ones; with a ``log`` as long as ``index``, their flat indices in
    its first places).

    With 'latest' beliefs ``seen`` holds each value's observation step and ``observed`` the
    receiver's, and the rule is :func:`latest_code`; when either is None it is
    :func:`grown_code`. The rule is chosen at compile time (numba prunes branches on an
    argument ``is None``), so each kind of belief gets its own machine code of the one loop.
    """
    cols = belief.shape[1]
    changed, r0, r1, c0, c1 = 0, belief.shape[0], 0, cols, 0
    for k in range(len(index)):
        r, c = index[k] // cols, index[k] % cols
        old, theirs = codes[r, c], values[k]
        if seen is None or observed is None:
            new = grown_code(old, theirs)
        else:
            new = latest_code(old, theirs, seen[k], observed, r, c)
        if new == old:
            continue
        # a value mixed from both sides (e.g. the receiver's obstacle with the sender's
        # safe flag) is news to the sender too: it counts as the receiver's own
        origin = sender if new == theirs else -1
        store(belief, safe, codes, stamps, tiles, origins, r, c, new, origin, tick)
        if log is not None:
            log[changed] = index[k]
        changed += 1
        r0, r1, c0, c1 = min(r0, r), max(r1, r + 1), min(c0, c), max(c1, c + 1)
    return changed, r0, r1, c0, c1
