"""Mapping by evidence (phase 3): a beam-model laser's scans weighed before the map believes them.

An exact laser's scan is folded as the truth (``knowledge/mapping.py``): its free polygon
is FREE, its hits are walls. A laser with a beam model (``world/beam.py``) lies: a short
or random return is a phantom obstacle, a random return beyond a wall a phantom opening.
Occupancy grid mapping weighs each reading as evidence instead (Thrun, Burgard and Fox,
*Probabilistic Robotics*, 9.2: log odds), which is what this fold does, in whole units:

* every cell of the scan's free polygon (the same polygon and chord band as the exact
  fold) is a *miss*: its evidence drops by :data:`MISS`; a ray the beam model left out
  (lost, filtered, no return) has length 0, so it pulls the outline in to the robot and
  a small obstacle between far rays is not swallowed (the chords into it run along its
  neighbours and cut no corner: ``chord_band`` skips them);
* the cell a return ended in is a *hit*: up by :data:`HIT` (a return's end is an
  obstacle whatever made it); and so is every cell between two consecutive returns closer
  than :data:`~.wall_marks.WALL_GAP` (the face between them, as the exact fold joins close
  hits; a phantom return is rarely that close to both neighbours);
* the evidence stays within ``[-CAP, CAP]``, so a cell that changes (a door that opens)
  is believed again after a few scans;
* the map then holds a cell FREE once its evidence is at most :data:`FREE_AT` (two
  misses), OCCUPIED once it is at least :data:`OCCUPIED_AT` (two hits), and otherwise
  what it held: an unknown cell stays unknown until two scans agree, one stray return
  makes no wall, one ray through a wall makes no opening.

The robot's own neighbourhood (``NEAR_ROBOT``) is FREE as in the exact fold; safe space
is this scan's free cells within the safe radius. The evidence grid is the robot's own
(``readings_feature.py`` keeps it): maps that arrive from teammates change the map,
not the evidence, and a later scan of the robot's own overrules them where its evidence
is decided.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from mresim_phys.knowledge.mapping import Update, fill_centres, polygon_window, scan_polygon
from mresim_phys.knowledge.scanfold import Pose, placement, turned
from mresim_phys.knowledge.wall_marks import NEAR_ROBOT, WALL_GAP, chord_band, hit_cell
from mresim_phys.types import FREE, OCCUPIED, UNKNOWN, BeliefGrid, BoolGrid, FloatArray
from mresim_phys.world.space import Scan

MISS = 1  # evidence a free cell of a scan loses
HIT = 3  # evidence the cell a return ended in gains
CAP = 12  # evidence stays within [-CAP, CAP]
FREE_AT = -2  # evidence at or below which the map holds a cell FREE
OCCUPIED_AT = 4  # evidence at or above which it holds it OCCUPIED


def integrate_evidence(
    scan: Scan,
    heading: float,
    maps: tuple[BeliefGrid, BoolGrid, np.ndarray],
    safe_radius: float,
    placed: Pose | None = None,
    observed: np.ndarray | None = None,
    step: int = 0,
) -> Update | None:
    """Weigh ``scan`` (cast facing ``heading``; read through a beam model) into a robot's
    ``maps`` (belief, safe cells, evidence), as it places the scan (``placed``, its
    believed pose; None: where it was cast); the cells the map now holds FREE that the scan
    saw. With ``observed`` ('latest' beliefs) the cells it decided are stamped ``step``."""
    belief, safe, evidence = maps
    where = placement((scan.origin[0], scan.origin[1], heading), placed)
    row0, col0, free = _place_evidence(
        float(scan.origin[0]), float(scan.origin[1]),
        np.ascontiguousarray(scan.angles, dtype=np.float64), scan.ranges, scan.normals,
        scan.wall_hit, float(scan.max_range), belief, safe, float(safe_radius), evidence,
        where, observed, step,
    )  # fmt: skip
    return None if row0 < 0 else Update(row0, col0, free.view(bool))


@njit(cache=True, nogil=True)
def _place_evidence(
    ox: float,
    oy: float,
    angles: FloatArray,
    ranges: FloatArray,
    normals: FloatArray,
    wall_hit: BoolGrid,
    max_range: float,
    belief: BeliefGrid,
    safe: BoolGrid,
    safe_radius: float,
    evidence: np.ndarray,
    placed: FloatArray,
    observed: np.ndarray | None,
    step: int,
) -> tuple[int, int, BeliefGrid]:
    """:func:`place_evidence` called from Python (a kernel of its own, as
    ``mapping._fold_alone``)."""
    return place_evidence(
        ox, oy, angles, ranges, normals, wall_hit, max_range, belief, safe, safe_radius,
        evidence, placed, observed, step,
    )  # fmt: skip


@njit(cache=True, nogil=True)
def fold_evidence(
    ox: float,
    oy: float,
    angles: FloatArray,
    ranges: FloatArray,
    normals: FloatArray,
    wall_hit: BoolGrid,
    max_range: float,
    belief: BeliefGrid,
    safe: BoolGrid,
    safe_radius: float,
    evidence: np.ndarray,
    observed: np.ndarray | None = None,
    step: int = 0,
) -> tuple[int, int, BeliefGrid]:
    """Weigh one scan into ``evidence`` and ``belief`` (module docstring); returns (row0,
    col0, mask of the window's cells the map now holds FREE that the scan saw) or
    row0 = -1 when the scan's window lies off the map. With ``observed`` ('latest'
    beliefs) every cell the scan decided was observed at ``step``."""
    n = len(angles)
    rows, cols = belief.shape
    ux, uy = np.cos(angles), np.sin(angles)
    ranges, wall_hit = ranges.copy(), wall_hit.copy()  # cut at known walls below
    for k in range(n):
        _clip_at_wall(ox, oy, ux[k], uy[k], ranges, wall_hit, k, evidence)
    ex, ey = ox + ranges * ux, oy + ranges * uy
    vx, vy, full = scan_polygon(ox, oy, angles, ex, ey)
    r0, r1, c0, c1 = polygon_window(vx, vy, rows, cols)
    if r0 >= r1 or c0 >= c1:
        return -1, -1, np.zeros((0, 0), np.uint8)
    seen = _polygon_mask(ox, oy, ux, uy, ex, ey, vx, vy, ranges, full, r0, c0, r1 - r0, c1 - c0)
    hits = _hit_cells(ex, ey, ux, uy, normals, wall_hit, ranges, max_range, evidence)
    for k in range(len(hits)):  # first: the one pass below then decides each seen cell
        evidence[hits[k, 0], hits[k, 1]] = min(evidence[hits[k, 0], hits[k, 1]] + HIT, CAP)
    _near_robot(ox, oy, belief, evidence, seen, r0, c0)
    h, w = seen.shape
    radius2 = safe_radius * safe_radius
    for r in range(h):  # misses, then believe; keep in ``seen`` the cells now FREE
        for c in range(w):
            if not seen[r, c]:
                continue
            evidence[r + r0, c + c0] = max(evidence[r + r0, c + c0] - MISS, -CAP)
            _believe(belief, evidence, observed, step, r + r0, c + c0)
            if belief[r + r0, c + c0] != FREE:
                seen[r, c] = 0
            elif (c + c0 + 0.5 - ox) ** 2 + (r + r0 + 0.5 - oy) ** 2 <= radius2:
                safe[r + r0, c + c0] = True
    for k in range(len(hits)):
        _believe(belief, evidence, observed, step, hits[k, 0], hits[k, 1])
    return r0, c0, seen


@njit(cache=True, nogil=True, inline="always")
def _believe(
    belief: BeliefGrid,
    evidence: np.ndarray,
    observed: np.ndarray | None,
    step: int,
    r: int,
    c: int,
) -> None:
    """Set the map's cell from its evidence where the evidence is decided (and, with
    ``observed``, stamp it observed at ``step``)."""
    if evidence[r, c] <= FREE_AT:
        belief[r, c] = FREE
    elif evidence[r, c] >= OCCUPIED_AT:
        belief[r, c] = OCCUPIED
    else:
        return
    if observed is not None:
        observed[r, c] = step


@njit(cache=True, nogil=True)
def _polygon_mask(
    ox: float,
    oy: float,
    ux: FloatArray,
    uy: FloatArray,
    ex: FloatArray,
    ey: FloatArray,
    vx: FloatArray,
    vy: FloatArray,
    ranges: FloatArray,
    full: bool,
    r0: int,
    c0: int,
    h: int,
    w: int,
) -> BeliefGrid:
    """The window's cells inside the scan's free polygon, less its chord band (the exact
    fold's fill, on window coordinates: nothing written to the map)."""
    n = len(ex)
    mask = np.zeros((h, w), np.uint8)
    chords = n if full else n - 1
    trimmed = chord_band(
        ox - c0, oy - r0, ux, uy, ex - c0, ey - r0, ranges, chords, mask, 0, 0, True
    )
    scratch = np.zeros((h, w), np.uint8)  # all UNKNOWN: the fill marks, collects no walls
    fill_centres(vx - c0, vy - r0, mask, scratch, 0, 0)
    for i in range(len(trimmed)):  # every band cell: the fill skipped them
        mask[trimmed[i, 0], trimmed[i, 1]] = 0
    return mask


@njit(cache=True, nogil=True)
def _clip_at_wall(
    ox: float,
    oy: float,
    ux: float,
    uy: float,
    ranges: FloatArray,
    wall_hit: BoolGrid,
    k: int,
    evidence: np.ndarray,
) -> None:
    """Walk ray ``k`` cell by cell (Amanatides and Woo) from the robot's neighbourhood to
    its reading; at the first cell the robot's evidence holds as a wall (at least
    :data:`OCCUPIED_AT`) short of the reading's end cell, that cell loses :data:`MISS` and
    the ray is cut where it enters it, with no return: a stray reading through a known
    wall frees nothing behind it, while a wall that has gone (a door opened) loses
    evidence to every ray through it until it is believed free."""
    rows, cols = evidence.shape
    length = ranges[k]
    r, c = math.floor(oy), math.floor(ox)
    step_c = 1 if ux > 0 else -1
    step_r = 1 if uy > 0 else -1
    big = 1e30
    next_x = (c + (1 if ux > 0 else 0) - ox) / ux if ux != 0.0 else big
    next_y = (r + (1 if uy > 0 else 0) - oy) / uy if uy != 0.0 else big
    delta_x = abs(1.0 / ux) if ux != 0.0 else big
    delta_y = abs(1.0 / uy) if uy != 0.0 else big
    t = 0.0
    while True:
        if next_x < next_y:
            t, c, next_x = next_x, c + step_c, next_x + delta_x
        else:
            t, r, next_y = next_y, r + step_r, next_y + delta_y
        if t >= length - 1e-9 or not (0 <= r < rows and 0 <= c < cols):
            return
        end = min(next_x, next_y)  # where the ray leaves this cell
        if t > NEAR_ROBOT and end < length and evidence[r, c] >= OCCUPIED_AT:
            evidence[r, c] = max(evidence[r, c] - MISS, -CAP)
            ranges[k], wall_hit[k] = t, False
            return


@njit(cache=True, nogil=True)
def _hit_cells(
    ex: FloatArray,
    ey: FloatArray,
    ux: FloatArray,
    uy: FloatArray,
    normals: FloatArray,
    wall_hit: BoolGrid,
    ranges: FloatArray,
    max_range: float,
    evidence: np.ndarray,
) -> np.ndarray:
    """(row, col) of every cell a hit counts for: each return's end cell, then the cells
    along the segment between two consecutive returns less than ``WALL_GAP`` apart that no
    scan has seen free (evidence at least 0: the exact fold also joins faces only over
    unknown cells), each segment's cells once."""
    n = len(ex)
    rows, cols = evidence.shape
    on = wall_hit & (ranges < max_range)
    out = np.empty((n + n * int(2 * WALL_GAP + 2), 2), np.int64)
    count = 0
    for k in range(n):
        if on[k]:
            r, c = hit_cell(ex[k], ey[k], ux[k], uy[k], normals[k, 0], normals[k, 1])
            if 0 <= r < rows and 0 <= c < cols:
                out[count, 0], out[count, 1] = r, c
                count += 1
    for k in range(n - 1):
        if not (on[k] and on[k + 1]):
            continue
        gx, gy = ex[k + 1] - ex[k], ey[k + 1] - ey[k]
        if gx * gx + gy * gy >= WALL_GAP * WALL_GAP:
            continue
        samples = int(2.0 * math.sqrt(gx * gx + gy * gy)) + 1
        last_r, last_c = -1, -1
        for s in range(1, samples):
            t = s / samples
            px, py = ex[k] + t * gx, ey[k] + t * gy
            r, c = hit_cell(px, py, ux[k], uy[k], normals[k, 0], normals[k, 1])
            inside = 0 <= r < rows and 0 <= c < cols
            if (r != last_r or c != last_c) and inside and evidence[r, c] >= 0:
                out[count, 0], out[count, 1] = r, c
                count += 1
                last_r, last_c = r, c
    return out[:count]


@njit(cache=True, nogil=True)
def _near_robot(
    ox: float,
    oy: float,
    belief: BeliefGrid,
    evidence: np.ndarray,
    seen: BeliefGrid,
    r0: int,
    c0: int,
) -> None:
    """The cells within ``NEAR_ROBOT`` of the robot are free (its body is there): FREE
    where unknown, with at least free evidence, and part of what the scan saw."""
    h, w = seen.shape
    for r in range(max(int(oy - NEAR_ROBOT) - 1, r0), min(int(oy + NEAR_ROBOT) + 2, r0 + h)):
        for c in range(max(int(ox - NEAR_ROBOT) - 1, c0), min(int(ox + NEAR_ROBOT) + 2, c0 + w)):
            if (c + 0.5 - ox) ** 2 + (r + 0.5 - oy) ** 2 <= NEAR_ROBOT * NEAR_ROBOT:
                seen[r - r0, c - c0] = 1
                evidence[r, c] = min(evidence[r, c], FREE_AT)
                if belief[r, c] == UNKNOWN:
                    belief[r, c] = FREE


@njit(cache=True, nogil=True)
def place_evidence(
    ox: float,
    oy: float,
    angles: FloatArray,
    ranges: FloatArray,
    normals: FloatArray,
    wall_hit: BoolGrid,
    max_range: float,
    belief: BeliefGrid,
    safe: BoolGrid,
    safe_radius: float,
    evidence: np.ndarray,
    placed: FloatArray,
    observed: np.ndarray | None = None,
    step: int = 0,
) -> tuple[int, int, BeliefGrid]:
    """:func:`fold_evidence` of a scan cast from (``ox``, ``oy``) as the robot places it
    (``placed``: x, y, turn; localisation), every ray and hit face turned by ``turn``."""
    bx, by, turn = placed[0], placed[1], placed[2]
    if bx == ox and by == oy and turn == 0.0:
        return fold_evidence(
            ox, oy, angles, ranges, normals, wall_hit, max_range, belief, safe, safe_radius,
            evidence, observed, step,
        )  # fmt: skip
    return fold_evidence(
        bx, by, angles + turn, ranges, turned(normals, turn), wall_hit, max_range, belief,
        safe, safe_radius, evidence, observed, step,
    )  # fmt: skip
