"""Communication models: disk, line of sight and path loss against hand-computed cases."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, example, given, settings
from hypothesis import strategies as st

from mresim_phys import COMM_MODELS
from mresim_phys.comms import Radios
from mresim_phys.comms.disk import DiskComm
from mresim_phys.comms.line_of_sight import LineOfSightComm
from mresim_phys.comms.params import DiskParams, LineOfSightParams, PathLossParams
from mresim_phys.comms.path_loss import PathLossComm
from mresim_phys.types import FloatArray
from mresim_phys.world.space import World
from mresim_phys.world.walls import segment_walls

WAF_FACTOR = 10 ** (-3.65 / 25)  # the original's range factor per wall: 0.714


def open_world(rows: int = 60, cols: int = 200) -> World:
    return World(np.zeros((rows, cols), dtype=bool), [1.0])


def walled_world(*wall_columns: int, thickness: int = 1) -> World:
    """A 60x200 world with full-height walls starting at the given columns."""
    occupied = np.zeros((60, 200), dtype=bool)
    for col in wall_columns:
        occupied[:, col : col + thickness] = True
    return World(occupied, [1.0])


def radios(*points: tuple[float, float], ranges: float | list[float] = 100.0) -> Radios:
    reach = ranges if isinstance(ranges, list) else [ranges] * len(points)
    return Radios.of(points, reach)


def disk_links(positions: list[tuple[float, float]], ranges: list[float]) -> np.ndarray:
    return DiskComm(DiskParams()).links(Radios.of(positions, ranges), open_world())


def path_loss(**params: object) -> PathLossComm:
    return PathLossComm(PathLossParams.model_validate(params))


def test_disk_links_when_closer_than_the_sum_of_ranges() -> None:
    links = disk_links([(0, 0), (25, 0), (60, 0)], [10, 20, 5])
    assert links[0, 1]  # 25 < 10 + 20
    assert not links[1, 2]  # 35 > 20 + 5
    assert not links[0, 2]
    assert not disk_links([(0, 0), (30, 0)], [10, 20])[0, 1]  # exactly the sum: not below it


def test_models_are_registered_and_unknown_models_suggest_names() -> None:
    assert COMM_MODELS.get("disk") is DiskComm
    assert COMM_MODELS.get("line_of_sight") is LineOfSightComm
    assert COMM_MODELS.get("path_loss") is PathLossComm
    with pytest.raises(KeyError, match="path_loss"):
        COMM_MODELS.get("pathloss")


def test_a_wall_between_two_robots_breaks_line_of_sight() -> None:
    model = LineOfSightComm(LineOfSightParams())
    world = walled_world(100)
    links = model.links(radios((90.5, 30.5), (110.5, 30.5), (60.5, 30.5)), world)
    assert not links[0, 1]  # 20 apart, in range, the wall between them
    assert links[0, 2]  # same side of the wall
    far_apart = radios((10.5, 30.5), (170.5, 30.5), ranges=50.0)
    assert not model.links(far_apart, open_world())[0, 1]  # 160 > 50 + 50


def test_line_of_sight_clearance_grazes_walls() -> None:
    occupied = np.zeros((60, 200), dtype=bool)
    occupied[31:, 100] = True  # a wall ending just below the sight line y = 30.5
    world = World(occupied, [1.0])
    pair = radios((90.5, 30.5), (110.5, 30.5))
    assert LineOfSightComm(LineOfSightParams()).links(pair, world)[0, 1]
    assert not LineOfSightComm(LineOfSightParams(clearance=0.6)).links(pair, world)[0, 1]


@pytest.mark.parametrize("walls", [0, 1, 2, 3])
def test_path_loss_range_shrinks_by_the_original_factor_per_wall(walls: int) -> None:
    world = walled_world(*[40 + 10 * k for k in range(walls)])
    model = path_loss()
    limit = 100.0 * WAF_FACTOR**walls  # the original's d < R * 0.714 ** W
    assert limit > 10 * walls  # the partner stands beyond every wall
    near, far = (
        radios((30.5, 30.5), (30.5 + limit - 0.2, 30.5)),
        radios((30.5, 30.5), (30.5 + limit + 0.2, 30.5)),
    )
    assert model.links(near, world)[0, 1]
    assert not model.links(far, world)[0, 1]


def test_path_loss_drops_by_waf_per_wall_and_the_cap_holds() -> None:
    model = path_loss(max_walls=2)
    assert np.allclose(
        model.attenuation(np.array([0, 1, 2, 5.0]), np.zeros(4)), [0, 3.65, 7.3, 7.3]
    )
    world = walled_world(40, 45, 50, 55, 60)  # five walls, counted as two
    pair = radios((30.5, 30.5), (30.5 + 100 * WAF_FACTOR**2 - 0.2, 30.5))
    assert model.links(pair, world)[0, 1]
    assert not path_loss().links(pair, world)[0, 1]  # uncapped: five walls


def test_a_thick_wall_counts_once_but_thickness_mode_charges_every_cell() -> None:
    thin, thick = walled_world(50), walled_world(50, thickness=8)
    pair = radios((30.5, 30.5), (90.5, 30.5))  # 60 apart: one wall allows 71.4
    assert path_loss().links(pair, thin)[0, 1] and path_loss().links(pair, thick)[0, 1]
    by_cell = path_loss(walls="thickness", cell_db=1.0)
    assert by_cell.links(pair, thin)[0, 1]  # 1 dB: 60 * 10 ** (1/25) = 66 is still < 100
    assert not by_cell.links(pair, thick)[0, 1]  # 8 dB: the range drops to 48


def test_heterogeneous_power_links_symmetrically_on_the_weaker_side() -> None:
    model = path_loss()
    world = open_world()
    strong = Radios.of([(20.5, 30.5), (140.5, 30.5)], [100.0, 100.0], [-80.0, np.nan])
    assert not model.links(strong, world)[0, 1]  # the default radio cannot answer from 120
    both = Radios.of([(20.5, 30.5), (140.5, 30.5)], [100.0, 100.0], [-80.0, -80.0])
    assert model.links(both, world)[0, 1]  # 100 * 10 ** (13 / 25) = 331 both ways


def test_default_path_loss_reaches_exactly_the_comm_range_in_free_space() -> None:
    model = path_loss()
    world = open_world(400, 400)
    angles = np.linspace(0, 2 * math.pi, 16, endpoint=False)
    reach = model.reach(radios((200.5, 200.5), ranges=150.0), 0, angles, world)
    assert np.allclose(reach, 150.0)


def test_path_loss_region_agrees_with_the_links_it_draws() -> None:
    rng = np.random.default_rng(2)
    occupied = rng.random((120, 160)) < 0.03
    occupied[55:65, 75:85] = False
    world = World(occupied, [1.0])
    for mode in ("count", "thickness"):
        model = path_loss(walls=mode, cell_db=0.5)
        here = (80.5, 60.5)
        angles = np.linspace(0, 2 * math.pi, 24, endpoint=False)
        reach = model.reach(radios(here, ranges=60.0), 0, angles, world)
        for angle, d in zip(angles, reach, strict=True):
            for scale, expected in ((0.98, True), (1.02, False)):
                there = (
                    here[0] + scale * d * math.cos(angle),
                    here[1] + scale * d * math.sin(angle),
                )
                linked = model.links(radios(here, there, ranges=60.0), world)[0, 1]
                assert linked == expected, (mode, angle, d, scale)


def test_line_of_sight_region_stops_at_walls() -> None:
    model = LineOfSightComm(LineOfSightParams())
    reach = model.reach(radios((90.5, 30.5)), 0, np.array([0.0, math.pi]), walled_world(100))
    assert reach[0] == pytest.approx(9.5)  # to the wall face at x = 100
    assert reach[1] == pytest.approx(90.5)  # to the map border at x = 0


def sampled_walls(occupied: np.ndarray, a: FloatArray, b: FloatArray) -> int | None:
    """Reference: separate obstacle runs met by a finely sampled segment; None when the
    samples jump diagonally between cells (the segment clips a corner cell more finely
    than the samples can see, so the reference cannot tell)."""
    t = np.linspace(0, 1, 40001)[:, None]
    xs, ys = (a + t * (b - a)).T
    rows, cols = np.floor(ys).astype(int), np.floor(xs).astype(int)
    if ((np.diff(rows) != 0) & (np.diff(cols) != 0)).any():
        return None
    inside = occupied[rows, cols].astype(int)
    return int(np.count_nonzero(np.diff(inside) == 1) + inside[0])


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1))
@example(1207665)  # the segment clips a corner cell between two samples
def test_wall_runs_match_a_finely_sampled_line(seed: int) -> None:
    rng = np.random.default_rng(seed)
    occupied = rng.random((30, 40)) < 0.3
    a, b = rng.uniform((0, 0), (40, 30), size=(2, 2))  # generic points: no exact corners
    runs, inside = segment_walls(occupied, a[0], a[1], b[0], b[1])
    expected = sampled_walls(occupied, a, b)
    assume(expected is not None)
    assert runs == expected
    assert 0.0 <= inside <= float(np.hypot(*(b - a))) + 1e-9
    assert (runs == 0) == (inside == 0.0)


MODELS = [
    DiskComm(DiskParams()),
    LineOfSightComm(LineOfSightParams()),
    path_loss(),
    path_loss(walls="thickness"),
]


@settings(max_examples=30, deadline=None)
@given(
    st.lists(
        st.tuples(st.floats(0.5, 199.5), st.floats(0.5, 59.5), st.floats(0, 80)),
        min_size=1,
        max_size=12,
    )
)
def test_links_are_symmetric_without_self_links(agents: list[tuple[float, float, float]]) -> None:
    world = walled_world(60, 130)
    points = Radios.of([(x, y) for x, y, _ in agents], [r for _, _, r in agents])
    for model in MODELS:
        links = model.links(points, world)
        assert np.array_equal(links, links.T)
        assert not links.diagonal().any()


def test_region_probe_draws_polygons_except_for_disks() -> None:
    from mresim_phys.comms.regions import REGION_RAYS, RegionProbe

    world = walled_world(100)
    ranges, powers = np.array([40.0, 40.0]), np.full(2, np.nan)
    positions = np.array([[90.5, 30.5], [20.5, 30.5]])
    assert RegionProbe(DiskComm(DiskParams()), ranges, powers, world)(positions) == [None, None]
    polygons = RegionProbe(path_loss(), ranges, powers, world)(positions)
    assert [p.shape for p in polygons] == [(REGION_RAYS, 2)] * 2
    east = polygons[0][0]  # ray 0 points along +x, through the wall at x = 100
    assert east[0] == pytest.approx(90.5 + 40.0 * WAF_FACTOR)
    assert np.allclose(np.hypot(*(polygons[1] - positions[1]).T), 40.0)  # open space
