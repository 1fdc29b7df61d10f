"""Mapping: a robot's own grid marks what its scans saw, and nothing else."""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np
import pytest
import shapely
from scipy import ndimage

from mresim_phys.agents import empty_belief
from mresim_phys.knowledge.coverage import Coverage
from mresim_phys.knowledge.mapping import NEAR_ROBOT, integrate_scan, merge_into
from mresim_phys.scenario.schema import SensorSpec
from mresim_phys.types import FREE, OCCUPIED, UNKNOWN
from mresim_phys.world.sensing import scan
from mresim_phys.world.space import Scan, World


def scanned_belief(
    truth: np.ndarray,
    poses: list[tuple[float, float, float]],
    rng_range: float = 60,
    fov_deg: float = 180.0,
):
    world = World(truth, [])
    belief, safe = empty_belief(truth.shape)
    updates = []
    sensor = SensorSpec(range=rng_range, fov_deg=fov_deg, rays=360 if fov_deg == 360 else 181)
    for x, y, heading in poses:
        result = scan(world, (x, y), heading, sensor, world.query_filter(None, False))
        updates.append(integrate_scan(belief, safe, result, 0.1))
    return belief, safe, updates


def test_hit_cells_are_true_walls_and_free_cells_are_almost_all_truly_free(
    rooms: np.ndarray,
) -> None:
    poses = [(10.5, 10.5, 0.0), (20.0, 30.0, 1.0), (30.0, 45.0, -2.0), (60.0, 30.0, 3.1)]
    belief, _, _ = scanned_belief(rooms, poses)
    assert np.all(rooms[belief == OCCUPIED])
    wrongly_free = np.count_nonzero(rooms & (belief == FREE)) / np.count_nonzero(belief == FREE)
    assert wrongly_free < 0.005
    assert np.count_nonzero(belief == FREE) > 500


def test_a_wall_seen_up_close_is_not_a_frontier(rooms: np.ndarray) -> None:
    """A straight wall in view is marked along its face: no unknown cell next to the free area."""
    belief, _, _ = scanned_belief(rooms, [(20.5, 30.5, 0.0)])
    face = belief[5:20, 40]  # the dividing wall above the door, seen from the left
    free_next = belief[5:20, 39]
    assert np.all(free_next == FREE)
    assert np.all(face == OCCUPIED)


def test_unseen_side_stays_unknown(rooms: np.ndarray) -> None:
    belief, _, _ = scanned_belief(rooms, [(10.5, 10.5, 0.0)])
    assert np.all(
        belief[2:20, 43:] == UNKNOWN
    )  # beyond the dividing wall, out of view through the door
    assert belief[10, 5] == UNKNOWN  # behind the robot (180 degree field of view)


def test_safe_space_is_free_and_near_the_robot(rooms: np.ndarray) -> None:
    belief, safe, _ = scanned_belief(rooms, [(20.5, 30.5, 0.0)])
    assert safe.any()
    assert np.all(belief[safe] == FREE)
    rows, cols = np.nonzero(safe)
    assert np.hypot(cols + 0.5 - 20.5, rows + 0.5 - 30.5).max() <= 0.1 * 60 + 1.5


def test_merge_known_beats_unknown_obstacle_beats_free() -> None:
    a = np.array([UNKNOWN, FREE, FREE, OCCUPIED], dtype=np.uint8)
    b = np.array([FREE, UNKNOWN, OCCUPIED, FREE], dtype=np.uint8)
    merge_into(a, b)
    assert a.tolist() == [FREE, FREE, OCCUPIED, OCCUPIED]


def test_coverage_counts_each_reachable_cell_once_and_never_decreases(rooms: np.ndarray) -> None:
    poses = [(10.5, 10.5, 0.0), (10.5, 10.5, 0.0), (20.0, 30.0, 1.0)]
    belief, _, updates = scanned_belief(rooms, poses)
    coverage = Coverage(~rooms)
    fractions = []
    for update in updates:
        coverage.touch(belief, update)
        coverage.settle()
        fractions.append(coverage.fraction)
    assert fractions == sorted(fractions) and fractions[0] == fractions[1]
    assert coverage.count == np.count_nonzero(coverage.known)
    assert coverage.count <= np.count_nonzero(belief != UNKNOWN)


def test_settling_touched_windows_counts_what_a_whole_map_count_gives() -> None:
    """``Coverage.settle`` reads only the touched windows, in one compiled pass a map: its
    count is the number of reachable cells some map holds FREE, and the cells it marks
    known are every FREE cell of the windows, reachable or not."""
    rng = np.random.default_rng(3)
    reachable = rng.random((50, 70)) < 0.8
    coverage = Coverage(reachable)
    maps = [np.zeros((50, 70), np.uint8) for _ in range(2)]
    for _ in range(12):
        belief = maps[int(rng.integers(0, 2))]
        r0, c0 = int(rng.integers(0, 40)), int(rng.integers(0, 60))
        r1, c1 = r0 + int(rng.integers(1, 10)), c0 + int(rng.integers(1, 10))
        belief[r0:r1, c0:c1] = np.maximum(
            belief[r0:r1, c0:c1], rng.integers(0, 3, (r1 - r0, c1 - c0))
        )
        coverage.touch_box(belief, (r0, r1, c0, c1))
        if rng.random() < 0.5:
            coverage.settle()
    coverage.settle()
    free = (maps[0] == FREE) | (maps[1] == FREE)
    ever_free = coverage.known
    assert coverage.count == np.count_nonzero(ever_free & reachable)
    assert (ever_free >= free).all()  # what is FREE now was counted (an obstacle may hide more)


def random_scans(truth: np.ndarray, count: int, seed: int) -> Iterator[Scan]:
    """Noise-free scans from random free poses (3x3 free around the robot), 1 degree apart."""
    world = World(truth, [])
    rng = np.random.default_rng(seed)
    rows, cols = np.nonzero(~truth)
    while count > 0:
        i = rng.integers(len(rows))
        x, y = cols[i] + rng.random(), rows[i] + rng.random()
        if truth[max(int(y) - 1, 0) : int(y) + 2, max(int(x) - 1, 0) : int(x) + 2].any():
            continue
        fov = float(rng.choice([60.0, 180.0, 270.0, 360.0]))
        rays = 360 if fov == 360.0 else int(fov) + 1
        sensor = SensorSpec(range=float(rng.uniform(8, 90)), fov_deg=fov, rays=rays)
        heading = float(rng.uniform(-np.pi, np.pi))
        yield scan(world, (x, y), heading, sensor, world.query_filter(None, False))
        count -= 1


def test_free_cells_are_the_cell_centres_inside_the_scan_polygon(rooms: np.ndarray) -> None:
    """The kernel's fill against shapely: it differs only on the polygon boundary.

    Cells near the robot are always free; cells on a chord between two ray ends
    farther than the nearer end are left out (the boundary rule). Everything else
    agrees with ``shapely.contains_xy`` on the cell centres.
    """
    agree = cells = 0
    for result in random_scans(rooms, 150, seed=7):
        belief, safe = empty_belief(rooms.shape)
        update = integrate_scan(belief, safe, result, 0.1)
        assert update is not None
        assert update.free.view(np.uint8).max() <= 1
        h, w = update.free.shape
        xs, ys = np.meshgrid(np.arange(w) + update.col0 + 0.5, np.arange(h) + update.row0 + 0.5)
        full_circle = len(result.angles) == 360  # no origin vertex: the fan closes
        origin = np.asarray(result.origin)[None, :]
        polygon = shapely.Polygon(result.ends if full_circle else np.vstack((origin, result.ends)))
        inside = shapely.contains_xy(polygon, xs, ys)
        near_robot = np.hypot(xs - result.origin[0], ys - result.origin[1]) <= NEAR_ROBOT
        extra = update.free & ~inside
        assert np.all(near_robot[extra])
        left_out = inside & ~update.free
        boundary = shapely.distance(polygon.exterior, shapely.points(xs[left_out], ys[left_out]))
        assert np.all(boundary <= 0.5 + 1e-9)
        assert np.count_nonzero(inside != update.free) <= 0.02 * h * w + 4
        agree += np.count_nonzero(inside == update.free)
        cells += h * w
        window = belief[update.row0 : update.row0 + h, update.col0 : update.col0 + w]
        assert np.all(window[update.free] != UNKNOWN)  # FREE, or OCCUPIED by a hit
    assert agree / cells >= 0.995


def test_noise_free_scans_mark_only_true_walls_occupied(rooms: np.ndarray) -> None:
    reachable = ndimage.label(~rooms)[0] == ndimage.label(~rooms)[0][30, 20]
    belief, safe = empty_belief(rooms.shape)
    for result in random_scans(rooms, 150, seed=11):
        integrate_scan(belief, safe, result, 0.1)
        hit = result.on_wall
        cells = np.floor(result.ends[hit] + 1e-3 * result.dirs[hit]).astype(int)
        assert np.all(rooms[cells[:, 1], cells[:, 0]])  # every hit cell is a true wall cell
        assert np.all(belief[cells[:, 1], cells[:, 0]] == OCCUPIED)
    assert np.all(rooms[belief == OCCUPIED])
    assert not np.any(reachable & (belief == OCCUPIED))
    assert np.count_nonzero(rooms & (belief == FREE)) < 0.005 * np.count_nonzero(belief == FREE)
    assert np.all(belief[safe] == FREE)


@pytest.mark.parametrize("wall", [(5, 5), (4, 4), (4, 5)])
def test_a_ray_grazing_a_wall_corner_marks_that_wall_not_the_free_cell_beyond(
    wall: tuple[int, int],
) -> None:
    """A 45 degree ray from a cell centre passes through cell corners; at the corner (5, 5)
    it touches whichever of the three cells beyond it is a wall, and the map marks that
    cell. It used to mark the cell just past the end point along the ray, (4, 5): a free
    cell beside a staircase wall when the wall was (5, 5) or (4, 4), a false wall on the
    robot's own side (mit_stata_basement: 150-230 per robot by step 600)."""
    grid = np.zeros((12, 12), dtype=bool)
    grid[wall] = True
    world = World(grid, [])
    angles = -math.pi / 4 + np.array([-0.2, 0.0, 0.2])
    result = world.cast_rays((3.5, 6.5), angles, 20.0, world.query_filter(None, False))
    assert result.wall_hit[1] and result.ranges[1] == pytest.approx(1.5 * math.sqrt(2))
    belief, safe = empty_belief(grid.shape)
    integrate_scan(belief, safe, result, 0.1)
    assert belief[wall] == OCCUPIED
    assert np.all(grid[belief == OCCUPIED])  # the free cells past the corner stay free


def test_a_full_circle_scan_leaves_no_gap_behind_the_robot() -> None:
    box = np.zeros((60, 60), dtype=bool)
    box[:2, :] = box[-2:, :] = box[:, :2] = box[:, -2:] = True
    belief, _, _ = scanned_belief(box, [(30.5, 30.5, 0.3)], rng_range=20.0, fov_deg=360.0)
    rows, cols = np.mgrid[:60, :60]
    within = np.hypot(cols + 0.5 - 30.5, rows + 0.5 - 30.5) <= 19.0
    assert np.all(belief[within] == FREE)


def test_a_false_wall_the_rays_go_through_is_cleared(rooms: np.ndarray) -> None:
    """A wall the robot's map holds where the truth is free (an earlier bump, a wall face
    joined across a doorway, a person who left) is FREE once a scan's rays pass through it;
    a false wall no ray crosses (behind the robot) stays."""
    belief, safe = empty_belief(rooms.shape)
    belief[28:33, 22:24] = OCCUPIED  # a stale obstacle right in front of the robot
    belief[29:32, 15:17] = OCCUPIED  # ... and one behind it (a 180-degree laser facing +x)
    world = World(rooms, [])
    result = scan(world, (20.5, 30.5), 0.0, SensorSpec(range=60), world.query_filter(None, False))
    update = integrate_scan(belief, safe, result, 0.1)
    assert update is not None and update.free[28 - update.row0, 22 - update.col0]
    assert np.all(belief[28:33, 22:24] == FREE)
    assert np.all(belief[29:32, 15:17] == OCCUPIED)
    assert np.all(belief[safe] == FREE)


def test_true_walls_known_from_the_start_are_never_cleared(rooms: np.ndarray) -> None:
    """Rays never pass through a true wall, so no scan from anywhere, at any range, field
    of view or ray count, clears a wall cell the map already holds (even a lone pillar
    between two rays far away)."""
    truth = rooms.copy()
    rng = np.random.default_rng(5)
    free_rows, free_cols = np.nonzero(~truth)
    pick = rng.choice(len(free_rows), 40, replace=False)
    truth[free_rows[pick], free_cols[pick]] = True  # lone one-cell pillars in open space
    belief, safe = empty_belief(truth.shape)
    belief[truth] = OCCUPIED
    for result in random_scans(truth, 150, seed=13):
        integrate_scan(belief, safe, result, 0.1)
    assert np.all(belief[truth] == OCCUPIED)


def test_a_pillar_between_two_far_rays_stays_a_wall() -> None:
    """Rays 1 degree apart pass 1.0 and 1.6 cells beside a one-cell pillar 150 cells away,
    and both go on: the pillar's centre is inside the scan's polygon, yet no ray crossed
    its inside, so the map keeps it (the fill alone would have called it free)."""
    box = np.zeros((200, 250), dtype=bool)
    box[:2, :] = box[-2:, :] = box[:, :2] = box[:, -2:] = True
    box[101, 170] = True
    belief, safe = empty_belief(box.shape)
    belief[101, 170] = OCCUPIED
    world = World(box, [])
    sensor = SensorSpec(range=240, fov_deg=180.0, rays=181)
    result = scan(world, (20.5, 100.5), 0.0, sensor, world.query_filter(None, False))
    assert not result.on_wall[90:92].any() or result.ranges[90:92].min() > 200
    integrate_scan(belief, safe, result, 0.1)
    assert belief[101, 170] == OCCUPIED
    assert belief[101, 160] == FREE


def test_degenerate_scans_do_not_break_the_update() -> None:
    angles = np.linspace(-np.pi / 2, np.pi / 2, 181)
    belief, safe = empty_belief((40, 40))
    zero = Scan((20.5, 20.5), angles, np.zeros(181), np.zeros((181, 2)), np.zeros(181, bool), 30.0)
    update = integrate_scan(belief, safe, zero, 0.1)
    assert update is not None and belief[20, 20] == FREE  # the robot's own cell
    assert np.count_nonzero(belief == FREE) <= 5
    off_grid = Scan((-50.0, -50.0), angles, np.full(181, 5.0), zero.normals, zero.wall_hit, 5.0)
    assert integrate_scan(belief, safe, off_grid, 0.1) is None
