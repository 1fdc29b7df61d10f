"""The laser beam model (``world/beam.py``) and mapping by evidence (``knowledge/evidence.py``):
each kind of reading has its distribution, the map weighs readings before it believes them,
and heavy noise on the office map leaves no phantom free space."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from scipy import ndimage, stats

from mresim_phys import Simulation
from mresim_phys.cli import main
from mresim_phys.knowledge.beamfold import BeamScanQueue
from mresim_phys.knowledge.evidence import OCCUPIED_AT, integrate_evidence
from mresim_phys.knowledge.frontiers import frontier_mask
from mresim_phys.knowledge.latest import LATEST
from mresim_phys.readings_feature import READINGS, ReadingCounts
from mresim_phys.types import FREE, OCCUPIED, UNKNOWN
from mresim_phys.world.beam import DRAWS, KINDS, Beam, read_beam
from mresim_phys.world.sensing import scan
from mresim_phys.world.space import Scan

RAYS = 20_000
TRUE = 30.0  # every ray's true distance in the synthetic scan
MAX = 100.0
OFFICE = Path(__file__).resolve().parent.parent / "scenarios" / "02_office_frontier.yaml"


def synthetic(true: float = TRUE) -> Scan:
    """RAYS rays over a half circle, each hitting a wall at ``true``."""
    angles = np.linspace(-np.pi / 2, np.pi / 2, RAYS)
    normals = np.column_stack((-np.cos(angles), -np.sin(angles)))
    return Scan((50.0, 50.0), angles, np.full(RAYS, true), normals, np.ones(RAYS, bool), MAX)


def read(beam: Beam, seed: int = 5, true: float = TRUE) -> tuple[Scan, np.ndarray]:
    counts = np.zeros(len(KINDS), np.int64)
    return read_beam(synthetic(true), beam, np.random.default_rng(seed), counts), counts


def test_hits_alone_read_the_true_distance_with_gaussian_noise() -> None:
    out, counts = read(Beam(sigma_hit=2.0))
    assert counts[0] == RAYS
    assert stats.kstest((out.ranges - TRUE) / 2.0, "norm").pvalue > 1e-3
    assert out.wall_hit.all()  # a hit keeps its wall and face
    np.testing.assert_array_equal(out.normals, synthetic().normals)


def test_short_returns_alone_follow_the_truncated_exponential() -> None:
    rate = 0.1
    out, counts = read(Beam(z_hit=0.0, z_short=1.0, lambda_short=rate))
    assert counts[1] == RAYS and (out.ranges <= TRUE).all()
    law = stats.truncexpon(b=rate * TRUE, scale=1 / rate)
    assert stats.kstest(out.ranges, law.cdf).pvalue > 1e-3
    assert out.wall_hit.all() and not out.normals.any()  # phantom: no face to join


@pytest.mark.parametrize(("max_free", "length"), [(None, MAX), (20.0, 20.0), (0.0, 0.0)])
def test_no_returns_alone_mark_no_obstacle_and_free_up_to_max_free(
    max_free: float | None, length: float
) -> None:
    out, counts = read(Beam(z_hit=0.0, z_max=1.0, max_free=max_free))
    assert counts[2] == RAYS
    assert (out.ranges == length).all() and not out.wall_hit.any()


def test_random_returns_alone_are_uniform_over_the_range() -> None:
    out, counts = read(Beam(z_hit=0.0, z_rand=1.0))
    assert counts[3] == RAYS
    assert stats.kstest(out.ranges, stats.uniform(0, MAX).cdf).pvalue > 1e-3


def test_a_ray_with_nothing_in_range_has_no_return_even_as_a_hit() -> None:
    out, _ = read(Beam(sigma_hit=1.0), true=MAX)
    assert (out.ranges == MAX).all() and not out.wall_hit.any()


def test_dropout_loses_its_share_of_rays() -> None:
    out, counts = read(Beam(dropout=0.3))
    lost = int(np.count_nonzero(out.ranges == 0))
    assert lost == counts[4] and counts[:4].sum() + lost == RAYS
    assert stats.binomtest(lost, RAYS, 0.3).pvalue > 1e-3


def test_a_scan_takes_the_same_draws_whatever_it_reads() -> None:
    rng = np.random.default_rng(9)
    read_beam(synthetic(), Beam(z_hit=0.5, z_rand=0.5), rng, np.zeros(len(KINDS), np.int64))
    skipped = np.random.default_rng(9)
    skipped.random((RAYS, DRAWS))
    assert rng.random() == skipped.random()


def test_the_speckle_filter_leaves_out_isolated_returns_only() -> None:
    ranges = np.array([10.0, 10.2, 25.0, 10.3, 10.1, 60.0, 100.0, 100.0])
    scan_in = Scan(
        (0.0, 0.0), np.linspace(0, 0.1, 8), ranges, np.zeros((8, 2)), ranges < 100, 100.0
    )
    counts = np.zeros(len(KINDS), np.int64)
    beam = Beam(speckle=1.0, speckle_window=1)
    out = read_beam(scan_in, beam, np.random.default_rng(1), counts)
    assert out.ranges[2] == 0.0 and out.ranges[5] == 0.0  # isolated: left out
    assert (out.ranges[[0, 1, 3, 4]] > 9).all() and counts[5] == 2


def evidence_maps(shape: tuple[int, int] = (40, 40)) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return np.zeros(shape, np.uint8), np.zeros(shape, bool), np.zeros(shape, np.int8)


def fan(ranges: list[float], hits: list[bool]) -> Scan:
    """Rays from (5.5, 20.5) spread over 0.2 rad around +x."""
    n = len(ranges)
    angles = np.linspace(-0.1, 0.1, n)
    return Scan((5.5, 20.5), angles, np.array(ranges), np.zeros((n, 2)), np.array(hits), 40.0)


def test_one_stray_return_makes_no_wall_and_two_do() -> None:
    maps = evidence_maps()
    ranges = [20.0] * 9
    ranges[4] = 10.2  # a short return in the middle of free space
    stray = fan(ranges, [True] * 9)
    integrate_evidence(stray, 0.0, maps, 3.0)
    cell = (20, 15)
    assert maps[0][cell] != OCCUPIED
    fresh = evidence_maps()
    for _ in range(2):
        integrate_evidence(fan([10.2] * 9, [True] * 9), 0.0, fresh, 3.0)
    assert fresh[0][cell] == OCCUPIED


def test_free_space_needs_two_scans_and_a_ray_through_a_known_wall_frees_nothing_behind() -> None:
    maps = evidence_maps()
    wall = fan([10.2] * 9, [True] * 9)
    integrate_evidence(wall, 0.0, maps, 3.0)
    assert maps[0][20, 10] == UNKNOWN  # one scan: no cell decided yet
    for _ in range(3):
        integrate_evidence(wall, 0.0, maps, 3.0)
    assert maps[0][20, 10] == FREE and maps[2][20, 15] >= OCCUPIED_AT
    for _ in range(3):  # readings through the known wall (a mirror, a random return)
        integrate_evidence(fan([30.0] * 9, [True] * 9), 0.0, maps, 3.0)
    assert maps[0][20, 15] == OCCUPIED
    assert (maps[0][18:23, 17:40] != FREE).all()


def office(tmp_path: Path, beam: dict[str, Any] | None, **top: Any) -> Path:
    data = yaml.safe_load(OFFICE.read_text(encoding="utf-8"))
    data["map"]["image"] = str((OFFICE.parent / data["map"]["image"]).resolve())
    if beam is not None:
        data["team"]["sensor"]["beam"] = beam
    data.update(top)
    path = tmp_path / f"office-{len(list(tmp_path.iterdir()))}.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return path


HEAVY = {
    "z_hit": 0.5, "z_short": 0.05, "z_max": 0.4, "z_rand": 0.05, "sigma_hit": 0.5,
    "max_free": 0, "speckle": 1.5,
}  # fmt: skip


def test_the_queued_scans_fold_as_the_scans_one_by_one(tmp_path: Path) -> None:
    sim = Simulation.from_yaml(office(tmp_path, HEAVY, steps=5))
    robot = sim.robots[0]
    laser, shapes = robot.laser, sim.senses.filter_of(robot)
    poses = [(40.0, 300.0, 0.0), (43.0, 300.5, 0.2), (46.0, 301.0, -0.4)]
    assert laser.beam is not None
    one = ReadingCounts.on(robot.belief.shape)
    maps = (robot.belief.copy(), robot.safe.copy(), one.evidence)
    rng = np.random.default_rng(4)
    for x, y, heading in poses:
        read = read_beam(
            scan(sim.world, (x, y), heading, laser, shapes), laser.beam, rng, one.counts
        )
        integrate_evidence(read, heading, maps, laser.safe_fraction * laser.range)
    queued = ReadingCounts.on(robot.belief.shape)
    holder = type("Holder", (), {"belief": robot.belief.copy(), "safe": robot.safe.copy()})()
    sinks = (queued.counts, queued.evidence)
    queue = BeamScanQueue(sim.world, laser, shapes, holder, np.random.default_rng(4), sinks)
    for x, y, heading in poses:
        queue.add((x, y), heading)
    queue.fold()
    assert np.array_equal(holder.belief, maps[0]) and np.array_equal(holder.safe, maps[1])
    assert np.array_equal(queued.evidence, one.evidence)
    assert np.array_equal(queued.counts, one.counts)


def frontier_clusters(belief: np.ndarray) -> tuple[int, int]:
    """(frontier clusters, clusters of at most 3 cells) of a map, 8-connected."""
    labels, count = ndimage.label(frontier_mask(belief), structure=np.ones((3, 3)))
    sizes = np.bincount(labels.ravel())[1:]
    return count, int(np.count_nonzero(sizes <= 3))


def false_free(sim: Simulation) -> int:
    """Cells the base holds FREE that are walls or outside the building in the truth."""
    return int(np.count_nonzero((sim.base.belief == FREE) & sim.world.occupied))


def test_heavy_max_range_noise_on_the_office_leaves_no_phantom_space(tmp_path: Path) -> None:
    """40 % of rays with no return, 10 % phantom returns: the team still explores the
    office, with no free space behind its walls or outside the building and no storm of
    frontiers (clusters and single specks, against the exact laser at the same coverage:
    at 90 % explored ~90 clusters, ~43 specks, against ~52 and ~27; no false free cell)."""
    stop = {"explored": 0.9}
    noisy = Simulation.from_yaml(office(tmp_path, HEAVY, stop=stop, steps=2500))
    exact = Simulation.from_yaml(office(tmp_path, None, stop=stop, steps=2500))
    assert noisy.run().explored >= 0.9 and exact.run().explored >= 0.9
    assert false_free(noisy) <= 10 and false_free(exact) <= 100
    storm = [frontier_clusters(r.belief) for r in noisy.robots]
    calm = [frontier_clusters(r.belief) for r in exact.robots]
    assert max(c for c, _ in storm) <= 3 * max(c for c, _ in calm)
    assert max(s for _, s in storm) <= 2 * max(s for _, s in calm) + 10  # specks
    readings = READINGS.value_in(noisy.robots[0].features)
    assert readings is not None and 0.3 < readings.max / readings.total < 0.5


def test_same_seed_same_bytes_with_and_without_threads(tmp_path: Path) -> None:
    path = office(tmp_path, HEAVY, steps=40)
    outs = []
    for threads in ("1", "2"):
        out = tmp_path / f"run{threads}"
        args = ["run", str(path), "--out", str(out), "--quiet", "--no-plots"]
        assert main([*args, "--threads", threads]) == 0
        outs.append((out / "metrics.csv").read_bytes())
    assert outs[0] == outs[1]
    assert b"noisy_readings" in outs[0].splitlines()[0]


def test_replay_recomputes_the_readings_and_the_metrics(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "run"
    path = office(tmp_path, HEAVY, steps=30)
    assert main(["run", str(path), "--out", str(out), "--quiet", "--no-plots"]) == 0
    assert main(["replay", str(out), "--metrics"]) == 0
    printed = capsys.readouterr().out
    assert "readings recomputed: identical" in printed and "DIFFERENT" not in printed


@pytest.mark.parametrize(
    ("beam", "field"),
    [
        ({"z_hit": 0.5, "z_max": 0.4}, "sum to 1"),
        ({"z_hit": 1.2, "z_max": -0.2}, "beam.z_hit"),
        ({"sigma_hit": -1}, "beam.sigma_hit"),
        ({"dropout": 1.0}, "beam.dropout"),
        ({"speckle": 0}, "beam.speckle"),
        ({"zhit": 1.0}, "beam.zhit"),
    ],
)
def test_bad_beam_input_is_one_paragraph_naming_the_field_and_exit_2(
    scenario_file: Any, capsys: pytest.CaptureFixture[str], beam: Any, field: str
) -> None:
    team = {"speed": 2, "radius": 1.0, "sensor": {"range": 30, "beam": beam}}
    assert main(["validate", str(scenario_file(team=team))]) == 2
    err = capsys.readouterr().err
    assert field in err and "Traceback" not in err and "scenario.yaml" in err


def test_range_noise_and_a_beam_model_together_are_refused(
    scenario_file: Any, capsys: pytest.CaptureFixture[str]
) -> None:
    sensor = {"range": 30, "noise_std": 0.5, "beam": {"sigma_hit": 0.5}}
    team = {"speed": 2, "radius": 1.0, "sensor": sensor}
    assert main(["validate", str(scenario_file(team=team))]) == 2
    assert "beam.sigma_hit" in capsys.readouterr().err


@pytest.mark.parametrize(
    "extra",
    [
        {"simulation": {"belief": "latest"}},
        {"team_localization": {"odometry": {"alpha": [0.0002, 1e-6, 0.0002, 1e-6]}}},
        {"team_localization": {"corrections": [{"kind": "scan_matching", "every": 1}]}},
    ],
)
def test_a_beam_model_runs_with_latest_beliefs_and_with_localisation(
    tmp_path: Path, extra: dict[str, Any]
) -> None:
    """The scans that fold one by one (latest beliefs stamp what they decide; a drifting
    robot weighs its scan where it believes it took it, after matching it) read through
    the model too: the team maps the office's first room, and with latest beliefs every
    cell a robot holds free was observed at some step."""
    top = {k: v for k, v in extra.items() if k != "team_localization"}
    path = office(tmp_path, HEAVY, steps=40, **top)
    if "team_localization" in extra:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
        data["team"]["localization"] = extra["team_localization"]
        path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    sim = Simulation.from_yaml(path)
    assert sim.run().explored > 0.02
    readings = READINGS.value_in(sim.robots[0].features)
    assert readings is not None and readings.total > 0
    observed = LATEST.state_of(sim.robots[0].features)
    if observed is not None:
        assert (observed[sim.robots[0].belief == FREE] >= 0).all()
