"""Phase 4b (planning): what the grid searches share, the move rule first.

The move rule of every grid search (``fields``' Dijkstra, ``astar``, ``jps``, the
topological map and planner) lives here, once:

* ``MOVES``: the 8 neighbour offsets (drow, dcol), in raster order; kernels that loop
  over them visit neighbours in that order, which decides ties between equal paths;
* ``STRAIGHT`` and ``DIAGONAL``: the cost of a move (octile: 1 and sqrt(2));
* the corner rule, ``passes_corner`` (and ``diagonal_ok`` on a flat mask): a diagonal
  move is forbidden only when BOTH orthogonal cells it squeezes between are blocked.

A kernel's neighbour loop reads::

    for dr, dc in MOVES:
        v = u + dr * wp + dc
        if not pad[v]:
            continue
        if dr != 0 and dc != 0:
            if not diagonal_ok(pad, wp, u, dr, dc):
                continue
            cost = here + DIAGONAL
        else:
            cost = here + STRAIGHT

The helpers are inlined (``inline="always"``), so the shared rule costs nothing over
writing it out. Keep the costs as constants inside the branch: a helper returning the
cost (or deciding diagonality itself) measured 5-10% slower in the Dijkstra kernel.
Numba's on-disk cache does not see edits here from the kernels of other modules: after
changing a helper, clear the ``__pycache__`` of ``planning/`` (or touch the kernels' files).

A search window is the bounding box of the passable cells, padded by one blocked cell so
the kernels need no bounds checks; node ``i`` of a window is padded cell
``(i // wp, i % wp)``. The numba pieces here are a binary heap ordered by ``(f, -g)``
(ties go to the deeper node, which keeps A* and JPS from widening over equal-cost
plateaus), the octile heuristic and the walk back along a predecessor array.
"""

from __future__ import annotations

import threading
import weakref
from collections.abc import Callable
from dataclasses import dataclass

import cv2
import numpy as np
from numba import njit
from numpy.typing import NDArray

from mresim_phys.types import BoolGrid, FloatArray

SQRT2 = float(np.sqrt(2.0))
NO_PRED = -1
TIE = 1e-9  # f values closer than this count as equal, and the deeper node goes first

MOVES: tuple[tuple[int, int], ...] = (
    (-1, -1), (-1, 0), (-1, 1), (0, -1), (0, 1), (1, -1), (1, 0), (1, 1),
)  # fmt: skip
FORWARD_MOVES = MOVES[4:]  # (0, 1), (1, -1), (1, 0), (1, 1): each undirected neighbour pair once
STRAIGHT = 1.0  # cost of a move along a row or a column
DIAGONAL = SQRT2  # cost of a diagonal move

Box = tuple[int, int, int, int]  # row0, row1, col0, col1 (half-open)


def union_box(a: Box | None, b: Box | None) -> Box | None:
    """The smallest box holding both (None is empty)."""
    if a is None or b is None:
        return a or b
    return min(a[0], b[0]), max(a[1], b[1]), min(a[2], b[2]), max(a[3], b[3])


@njit(cache=True, nogil=True, inline="always")
def passes_corner(beside_row: bool, beside_col: bool) -> bool:
    """The corner rule, given whether the two cells a diagonal move squeezes between are
    passable (the one its row step reaches and the one its column step reaches): the move
    is forbidden only when both are blocked."""
    return beside_row or beside_col


@njit(cache=True, nogil=True, inline="always")
def diagonal_ok(pad: NDArray[np.bool_], wp: int, u: int, dr: int, dc: int) -> bool:
    """The corner rule for the DIAGONAL move by (dr, dc) from flat cell ``u`` of a mask of
    row width ``wp``: ``passes_corner`` of cells ``u + (dr, 0)`` and ``u + (0, dc)``.
    Straight moves have no corner; whether the target is passable is the caller's test."""
    return passes_corner(pad[u + dr * wp], pad[u + dc])


@njit(cache=True, nogil=True)
def flat_moves(wp: int) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.int64]]:
    """``MOVES`` as flat index offsets on a mask of row width ``wp`` (same order), and for
    each the offsets of the two cells a diagonal squeezes between (the one its row step
    reaches, the one its column step reaches; both 0 for a straight move). A kernel that
    loops over these reads each neighbour as ``u + step[k]`` and applies the corner rule as
    ``passes_corner(pad[u + beside_row[k]], pad[u + beside_col[k]])`` when both are
    non-zero: the same rule as :func:`diagonal_ok`, ~25 % faster in the Dijkstra kernel
    than unpacking ``(dr, dc)`` pairs."""
    step = np.empty(len(MOVES), dtype=np.int64)
    beside_row = np.zeros(len(MOVES), dtype=np.int64)
    beside_col = np.zeros(len(MOVES), dtype=np.int64)
    for k in range(len(MOVES)):
        dr, dc = MOVES[k]
        step[k] = dr * wp + dc
        if dr != 0 and dc != 0:
            beside_row[k], beside_col[k] = dr * wp, dc
    return step, beside_row, beside_col


def bbox(mask: BoolGrid) -> Box | None:
    """Half-open bounding box (row0, row1, col0, col1) of the True cells, None if none.

    A C-contiguous 2-D mask goes through ``cv2.boundingRect`` (half the time of two
    ``any`` reductions on an 800x600 mask)."""
    if mask.ndim == 2 and mask.flags.c_contiguous and mask.size:
        col0, row0, w, h = cv2.boundingRect(mask.view(np.uint8))
        return None if w == 0 else (row0, row0 + h, col0, col0 + w)
    rows = np.flatnonzero(mask.any(axis=1))
    if rows.size == 0:
        return None
    cols = np.flatnonzero(mask[rows[0] : rows[-1] + 1].any(axis=0))
    return int(rows[0]), int(rows[-1]) + 1, int(cols[0]), int(cols[-1]) + 1


_KNOWN = threading.local()  # per thread: (weak reference to a mask, its whole window)


def remember_window(passable: BoolGrid, window: Window) -> None:
    """Note that ``window`` is ``Window.of(passable)``, so that the next ``Window.of`` of the
    same array on this thread takes it instead of finding the box and copying the mask
    again (a robot's replan builds it for its own search, then its planner asks for it:
    ~0.1 ms a replan on the library). The mask must not change afterwards (nothing writes
    a passable mask in place); a new mask replaces the note."""
    _KNOWN.window = (weakref.ref(passable), window)


def forget_window(passable: BoolGrid) -> None:
    """Drop the note of :func:`remember_window` if it is of ``passable``: its cells are about
    to be rewritten (``fields.passable_cells`` reuses a mask nobody holds any more)."""
    known = getattr(_KNOWN, "window", None)
    if known is not None and known[0]() is passable:
        _KNOWN.window = None


@dataclass(frozen=True)
class Window:
    """A padded search window over a passable mask (flat, blocked border)."""

    pad: NDArray[np.bool_]  # flat (hp * wp,) passable mask, border blocked
    wp: int
    origin: tuple[int, int]  # full-grid (row, col) of padded element [0, 0]

    @classmethod
    def around(cls, passable: BoolGrid, box: Box) -> Window:
        """The window of ``passable[r0:r1, c0:c1]`` with a one-cell blocked border."""
        r0, r1, c0, c1 = box
        pad = np.zeros((r1 - r0 + 2, c1 - c0 + 2), dtype=np.bool_)
        pad[1:-1, 1:-1] = passable[r0:r1, c0:c1]
        return cls(pad.ravel(), c1 - c0 + 2, (r0 - 1, c0 - 1))

    @classmethod
    def of(cls, passable: BoolGrid) -> Window | None:
        """The window over the bounding box of every passable cell (None if there is none);
        the one :func:`remember_window` noted for this very mask on this thread, if any."""
        known = getattr(_KNOWN, "window", None)
        if known is not None and known[0]() is passable:
            window: Window = known[1]
            return window
        box = bbox(passable)
        return None if box is None else cls.around(passable, box)

    def node(self, rc: tuple[int, int]) -> int:
        """Flat window index of full-grid cell ``rc``."""
        return (rc[0] - self.origin[0]) * self.wp + (rc[1] - self.origin[1])

    def node_inside(self, rc: tuple[int, int]) -> int | None:
        """Flat window index of full-grid cell ``rc``; None where it lies outside the window."""
        r, c = rc[0] - self.origin[0], rc[1] - self.origin[1]
        inside = 0 <= r < self.pad.size // self.wp and 0 <= c < self.wp
        return r * self.wp + c if inside else None

    def padded(self, grid: FloatArray) -> FloatArray:
        """A full-grid float array cut to this window, flat, its border 1.0 (never entered)."""
        hp = self.pad.size // self.wp
        r0, c0 = self.origin[0] + 1, self.origin[1] + 1
        out = np.ones((hp, self.wp))
        out[1:-1, 1:-1] = grid[r0 : r0 + hp - 2, c0 : c0 + self.wp - 2]
        return out.ravel()

    def points(self, nodes: NDArray[np.int64]) -> FloatArray:
        """World (x, y) cell centres (n, 2) of flat window indices."""
        rows, cols = np.divmod(np.asarray(nodes, dtype=np.int64), self.wp)
        return np.column_stack((cols + self.origin[1] + 0.5, rows + self.origin[0] + 0.5))


UNSEEN, OPEN, CLOSED = 0, 1, 2  # search state of a cell


def search_window(
    passable: BoolGrid,
    start: tuple[int, int],
    goal: tuple[int, int],
    engine: Callable[[Window, tuple[int, int], tuple[int, int]], tuple[FloatArray, int]],
) -> FloatArray:
    """The path ``engine`` (a window search returning (path, expansions)) finds."""
    window = Window.of(passable)
    assert window is not None  # the start is passable
    return engine(window, start, goal)[0]


def search_arrays(size: int) -> tuple[FloatArray, NDArray[np.int64], NDArray[np.uint8]]:
    """Cost, predecessor and state arrays for one search over ``size`` cells.

    Cost and predecessor are left uninitialised (``np.empty``) and read only where the state
    is not UNSEEN; the state is ``np.zeros`` (calloc). Large blocks come from fresh
    zero-filled pages that the OS maps only when touched, so a search that touches few
    cells (JPS in open space) costs little even on a 2000x2000 window, where filling the
    three arrays would take ~30 ms.
    """
    return np.empty(size), np.empty(size, dtype=np.int64), np.zeros(size, dtype=np.uint8)


@njit(cache=True, nogil=True, inline="always")
def octile(r0: int, c0: int, r1: int, c1: int) -> float:
    """Octile distance between two cells: the path cost on an obstacle-free grid."""
    dr, dc = abs(r1 - r0), abs(c1 - c0)
    return max(dr, dc) + (SQRT2 - 1.0) * min(dr, dc)


@njit(cache=True, nogil=True, inline="always")
def _before(fa: float, ga: float, fb: float, gb: float) -> bool:
    """Heap order: smaller f first; within TIE, larger g first. Written without branches
    (the same truth value for every input, NaN included), so a step down the heap picks
    its child with a conditional move instead of a branch that mispredicts half the time:
    ~1.2x faster A* on the rooms map, the same searches."""
    return (fa < fb - TIE) | ((not fa > fb + TIE) & (ga > gb))


HeapStorage = FloatArray  # (capacity, 3) rows (f, g, node): one row a heap entry


@njit(cache=True, nogil=True)
def heap_new(capacity: int) -> HeapStorage:
    """Empty heap storage: a row (key f, depth g, node) per entry. The three fields of an
    entry sit side by side, so a step down the heap reads one place in memory, not three
    arrays (~1.2x faster A* than three arrays, in the same order of operations); a node is
    an integer held exactly in a float64 (below 2**53)."""
    return np.empty((max(capacity, 16), 3))


@njit(cache=True, nogil=True)
def heap_grow(heap: HeapStorage) -> HeapStorage:
    """The heap storage with twice the capacity (called by a kernel when it is full)."""
    return np.concatenate((heap, np.empty_like(heap)))


@njit(cache=True, nogil=True)
def heap_push(heap: HeapStorage, size: int, f: float, g: float, n: int) -> int:
    """Push ``(f, g, n)`` (the caller ensures ``size < capacity``); returns the new size."""
    i = size
    while i > 0:
        parent = (i - 1) >> 1
        if not _before(f, g, heap[parent, 0], heap[parent, 1]):
            break
        heap[i, 0], heap[i, 1], heap[i, 2] = heap[parent, 0], heap[parent, 1], heap[parent, 2]
        i = parent
    heap[i, 0], heap[i, 1], heap[i, 2] = f, g, n
    return size + 1


@njit(cache=True, nogil=True, inline="always")
def heap_add(heap: HeapStorage, size: int, f: float, g: float, n: int) -> tuple[HeapStorage, int]:
    """Push ``(f, g, n)``, doubling the storage first when it is full; the storage and the
    new size."""
    if size == len(heap):
        heap = heap_grow(heap)
    return heap, heap_push(heap, size, f, g, n)


@njit(cache=True, nogil=True, inline="always")
def heap_start(capacity: int, source: int, f: float) -> tuple[HeapStorage, int]:
    """Heap storage holding only ``source`` at key ``f`` and depth 0; the storage, size 1."""
    heap = heap_new(capacity)
    return heap, heap_push(heap, 0, f, 0.0, source)


@njit(cache=True, nogil=True, inline="always")
def pop_open(heap: HeapStorage, size: int, state: NDArray[np.uint8]) -> tuple[int, int]:
    """Pop entries until one whose node is not CLOSED, and close it: (the node, the new
    size); the node is -1 once the heap is empty (entries of closed nodes are stale)."""
    while size > 0:
        u, size = heap_pop(heap, size)
        if state[u] != CLOSED:
            state[u] = CLOSED
            return u, size
    return -1, 0


@njit(cache=True, nogil=True)
def heap_pop(heap: HeapStorage, size: int) -> tuple[int, int]:
    """Remove the first entry; returns (its node, the new size)."""
    top = int(heap[0, 2])
    size -= 1
    f, g, n = heap[size, 0], heap[size, 1], heap[size, 2]
    i = 0
    while True:
        child = 2 * i + 1
        if child >= size:
            break
        if child + 1 < size:
            child += _before(heap[child + 1, 0], heap[child + 1, 1], heap[child, 0], heap[child, 1])
        if not _before(heap[child, 0], heap[child, 1], f, g):
            break
        heap[i, 0], heap[i, 1], heap[i, 2] = heap[child, 0], heap[child, 1], heap[child, 2]
        i = child
    heap[i, 0], heap[i, 1], heap[i, 2] = f, g, n
    return top, size


@njit(cache=True, nogil=True)
def walk_back(pred: NDArray[np.integer], target: int) -> NDArray[np.int64]:
    """Nodes from the root of ``pred`` to ``target`` (``pred[root] == NO_PRED``)."""
    count, node = 1, target
    while pred[node] != NO_PRED:
        node = pred[node]
        count += 1
    out = np.empty(count, dtype=np.int64)
    node = target
    for i in range(count - 1, -1, -1):
        out[i] = node
        node = pred[node]
    return out
