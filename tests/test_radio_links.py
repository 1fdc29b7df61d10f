"""Radio links: shadowing, fast fading, Gilbert-Elliott bursts, loss tables and traces
(``comms/radio.py`` and its parts), and the scenario errors they can raise."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mresim_phys import Simulation
from mresim_phys.cli import main
from mresim_phys.comms.base import Radios
from mresim_phys.comms.bursts import GilbertElliott
from mresim_phys.comms.params import PathLossParams
from mresim_phys.comms.path_loss import PathLossComm
from mresim_phys.comms.radio import LinkLayer
from mresim_phys.comms.radio_params import BurstSpec, RadioSpec, ShadowingSpec
from mresim_phys.comms.shadowing import Shadowing, correlation, shadow_field
from mresim_phys.comms.traces import LinkTrace, LossTable, TraceError, parse_trace
from mresim_phys.world.space import World


def lag_correlation(field: np.ndarray, lag: int) -> float:
    """The empirical correlation of ``field`` with itself ``lag`` cells along rows and columns."""
    a = np.concatenate([field[:, :-lag].ravel(), field[:-lag, :].ravel()])
    b = np.concatenate([field[:, lag:].ravel(), field[lag:, :].ravel()])
    return float(np.corrcoef(a, b)[0, 1])


def test_shadow_field_has_unit_variance_and_the_documented_variogram() -> None:
    length = 12.0
    fields = [shadow_field((300, 300), length, np.random.default_rng(s)) for s in range(4)]
    assert np.mean([f.var() for f in fields]) == pytest.approx(1.0, abs=0.08)
    for lag in (3, 6, 12, 24):
        measured = np.mean([lag_correlation(f, lag) for f in fields])
        # the semivariogram gamma(h) = 1 - rho(h) of a unit field
        assert 1 - measured == pytest.approx(1 - correlation(lag, length), abs=0.06)
    assert fields[0].dtype == np.float32


def test_shadow_field_is_as_strong_at_the_map_edge_as_in_the_middle() -> None:
    fields = [shadow_field((120, 120), 10.0, np.random.default_rng(s)) for s in range(30)]
    edge = np.concatenate([f[:, :3].ravel() for f in fields])
    middle = np.concatenate([f[:, 58:61].ravel() for f in fields])
    assert edge.var() == pytest.approx(middle.var(), rel=0.2)


def test_pair_shadowing_is_symmetric_and_has_the_given_sigma() -> None:
    spec = ShadowingSpec(sigma_db=6.0, length=10.0)
    rng = np.random.default_rng(1)
    values = []
    for seed in range(40):
        shadow = Shadowing.build(spec, (200, 200), np.random.default_rng(seed), rng)
        positions = rng.uniform(0, 200, size=(12, 2))
        rows, cols = np.triu_indices(12, k=1)
        forward = shadow.pair_db(positions, rows, cols)
        np.testing.assert_array_equal(forward, shadow.pair_db(positions, cols, rows))
        values.append(forward)
    assert np.concatenate(values).std() == pytest.approx(6.0, rel=0.12)


def test_a_pair_moving_less_than_the_length_keeps_nearly_the_same_shadowing() -> None:
    spec = ShadowingSpec(sigma_db=8.0, length=40.0)
    shadow = Shadowing.build(spec, (200, 200), np.random.default_rng(3), np.random.default_rng(4))
    rows, cols = np.array([0]), np.array([1])
    start = np.array([[50.0, 50.0], [150.0, 120.0]])
    moves = [start + np.array([[k, 0.0], [0.0, k]]) for k in range(6)]
    steps = [shadow.pair_db(moved, rows, cols)[0] for moved in moves]
    assert np.ptp(steps) < 2.0  # dB over 5 cells of a 40-cell correlation length


def office_world() -> World:
    occupied = np.zeros((100, 200), dtype=bool)
    occupied[:, 100] = True  # one wall across the map
    return World(occupied, [])


def radios_on_a_line(n: int) -> Radios:
    positions = np.column_stack([np.linspace(10, 190, n), np.full(n, 50.0)])
    return Radios.of(positions, np.full(n, 40.0))


def test_zero_shadowing_gives_exactly_the_models_links() -> None:
    model = PathLossComm(PathLossParams())
    radios, world = radios_on_a_line(9), office_world()
    spec = RadioSpec(shadowing=ShadowingSpec(sigma_db=0.0, length=10.0))
    rng = np.random.default_rng(0)
    layer = LinkLayer(spec, 9, shadowing=Shadowing.build(spec.shadowing, (100, 200), rng, rng))  # type: ignore[arg-type]
    np.testing.assert_array_equal(
        layer.model_links(model, radios, world), model.links(radios, world)
    )


def test_shadowing_carries_some_links_past_the_models_reach_and_cuts_others() -> None:
    model = PathLossComm(PathLossParams())
    radios, world = radios_on_a_line(15), office_world()
    plain = model.links(radios, world)
    gained = lost = 0
    for seed in range(10):
        spec = RadioSpec(shadowing=ShadowingSpec(sigma_db=8.0, length=20.0))
        rng = np.random.default_rng(seed)
        shadow = Shadowing.build(spec.shadowing, (100, 200), rng, rng)  # type: ignore[arg-type]
        links = LinkLayer(spec, 15, shadowing=shadow).model_links(model, radios, world)
        assert links is not None
        np.testing.assert_array_equal(links, links.T)
        gained += int(np.count_nonzero(links & ~plain))
        lost += int(np.count_nonzero(plain & ~links))
    assert gained > 0 and lost > 0


def test_fast_fading_changes_links_from_step_to_step() -> None:
    model = PathLossComm(PathLossParams())
    radios, world = radios_on_a_line(15), office_world()
    spec = RadioSpec(shadowing=ShadowingSpec(sigma_db=0.0, length=20.0, fading_db=6.0))
    rng = np.random.default_rng(0)
    layer = LinkLayer(spec, 15, shadowing=Shadowing.build(spec.shadowing, (100, 200), rng, rng))  # type: ignore[arg-type]
    draws = {layer.model_links(model, radios, world).tobytes() for _ in range(6)}  # type: ignore[union-attr]
    assert len(draws) > 1


def test_gilbert_elliott_loss_matches_its_stationary_rate_and_comes_in_bursts() -> None:
    spec = BurstSpec(good_to_bad=0.05, bad_to_good=0.25, loss_good=0.02, loss_bad=0.8)
    chain = GilbertElliott(spec, 6, np.random.default_rng(7))  # 15 pairs
    lost = np.array([chain.step() for _ in range(6000)])
    assert lost.mean() == pytest.approx(spec.stationary_loss, abs=0.01)
    # bursts: a loss is far likelier right after a loss than on average
    after_loss = lost[1:][lost[:-1]].mean()
    assert after_loss > spec.stationary_loss + 0.2


def test_gilbert_elliott_lost_matrix_is_symmetric() -> None:
    spec = BurstSpec(good_to_bad=0.5, bad_to_good=0.5)
    lost = GilbertElliott(spec, 5, np.random.default_rng(0)).lost(5)
    np.testing.assert_array_equal(lost, lost.T)
    assert not lost.diagonal().any()


def test_a_burst_spec_that_never_moves_is_refused() -> None:
    with pytest.raises(ValueError, match="never moves"):
        BurstSpec(good_to_bad=0.0, bad_to_good=0.0)


def test_loss_table_interpolates_in_distance_within_the_wall_count() -> None:
    rows = [(0, 0.0, 0.0), (0, 100.0, 1.0), (2, 0.0, 0.5), (2, 10.0, 1.0)]
    table = LossTable(rows, np.random.default_rng(0))
    walls = np.array([0, 0, 1, 2, 5, 0])
    distance = np.array([50.0, 150.0, 25.0, 5.0, 20.0, 0.0])
    # one wall has no rows: the rows of 0 walls apply; beyond the last distance, the last loss
    np.testing.assert_allclose(table.loss(walls, distance), [0.5, 1.0, 0.25, 0.75, 1.0, 0.0])


def test_loss_table_without_rows_for_zero_walls_is_refused() -> None:
    with pytest.raises(TraceError, match="0 walls"):
        LossTable([(1, 0.0, 0.1)], np.random.default_rng(0))


NAMES = ["base", "A", "B", "C"]


def test_trace_rows_force_links_up_and_down_from_their_step_on() -> None:
    text = "step,a,b,up,loss\n0,A,B,1,\n5,A,B,0,\n5,base,C,,1\n8,B,A,,\n"
    trace = LinkTrace(parse_trace(text, NAMES), 4, np.random.default_rng(0))
    speaking = np.ones(4, dtype=bool)
    model = np.zeros((4, 4), dtype=bool)
    model[0, 3] = model[3, 0] = True
    at = [trace.apply(model, speaking, step) for step in range(10)]
    assert at[0][1, 2] and at[4][2, 1] and not at[5][1, 2] and not at[7][1, 2]
    assert at[4][0, 3] and not at[5][0, 3] and not at[9][0, 3]  # loss 1 from step 5
    assert not at[9][1, 2]  # step 8: blank row, back to the model (unlinked)
    silent = np.array([True, True, False, True])
    assert not trace.apply(np.ones((4, 4), dtype=bool), silent, 10)[1, 2]


@pytest.mark.parametrize(
    ("text", "problem"),
    [
        ("step,a,b,up\n0,A,Z,1\n", "not an agent"),
        ("step,a,b,up\n5,A,B,1\n3,A,C,1\n", "sort by step"),
        ("step,a,b,up\n0,A,A,1\n", "two agents"),
        ("step,a,b,up\n0,A,B,2\n", "give 1, 0"),
        ("step,a,b,loss\n0,A,B,1.5\n", "from 0 to 1"),
        ("step,a,b,capacity\n0,A,B,-3\n", "capacity"),
        ("step,a,b\n0,A,B\n", "at least one of"),
        ("step,a,b,up,colour\n0,A,B,1,red\n", "unknown"),
        ("step,a,b,up\nx,A,B,1\n", "not a number"),
    ],
)
def test_a_bad_trace_names_its_line(text: str, problem: str) -> None:
    with pytest.raises(TraceError, match=problem):
        parse_trace(text, NAMES)


def run_validate(scenario_file: Any, **communication: Any) -> int:
    return main(["validate", str(scenario_file(communication=communication))])


@pytest.mark.parametrize(
    ("communication", "field"),
    [
        ({"capacity": -5}, "communication.capacity"),
        ({"capacity": 0}, "communication.capacity"),
        ({"latency": -1}, "communication.latency"),
        ({"bursts": {"good_to_bad": 1.5, "bad_to_good": 0.1}}, "communication.bursts.good_to_bad"),
        ({"bursts": {"good_to_bad": 0.1, "bad_to_good": 0.1, "loss_bad": -0.1}}, "loss_bad"),
        ({"shadowing": {"sigma_db": -2, "length": 10}}, "communication.shadowing.sigma_db"),
        ({"shadowing": {"sigma_db": 2, "length": 0}}, "communication.shadowing.length"),
        ({"model": "disk", "shadowing": {"sigma_db": 2, "length": 9}}, "no signal in dB"),
        ({"maps": "full", "capacity": 100}, "communication.maps"),
        ({"loss_table": [[1, 0, 0.1]]}, "communication.loss_table"),
        ({"loss_table": [[0, 0, 1.1]]}, "communication.loss_table"),
        ({"trace": "missing.csv"}, "communication.trace"),
        ({"priority": "loudest", "capacity": 9}, "communication.priority"),
        ({"control": {"capacity": -1}}, "communication.control.capacity"),
    ],
)
def test_bad_radio_input_is_one_paragraph_naming_the_field_and_exit_2(
    scenario_file: Any, capsys: pytest.CaptureFixture[str], communication: Any, field: str
) -> None:
    base = {"model": "path_loss"} if "model" not in communication else {}
    assert run_validate(scenario_file, **base, **communication) == 2
    err = capsys.readouterr().err
    assert field in err and "Traceback" not in err


def test_a_trace_naming_an_unknown_robot_fails_at_validation(
    scenario_file: Any, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "links.csv").write_text("step,a,b,up\n0,A,Q,1\n", encoding="utf-8")
    assert run_validate(scenario_file, trace="links.csv") == 2
    err = capsys.readouterr().err
    assert "communication.trace" in err and "line 2" in err and "'Q'" in err


def test_a_trace_links_two_robots_out_of_range_for_its_steps(
    scenario_file: Any, tmp_path: Path
) -> None:
    (tmp_path / "links.csv").write_text("step,a,b,up\n0,base,B,0\n0,A,B,1\n", encoding="utf-8")
    path = scenario_file(communication={"model": "disk", "trace": "links.csv"})
    sim = Simulation.from_yaml(path, steps=5)
    for _ in range(5):
        sim.step()
        assert sim.links[1, 2] and not sim.links[0, 2]


def all_options(tmp_path: Path) -> dict[str, Any]:
    (tmp_path / "links.csv").write_text("step,a,b,up,loss\n10,A,B,,0.5\n", encoding="utf-8")
    return {
        "model": "path_loss",
        "dropout": 0.05,
        "shadowing": {"sigma_db": 4, "length": 15, "fading_db": 1},
        "bursts": {"good_to_bad": 0.1, "bad_to_good": 0.3, "loss_bad": 0.7},
        "loss_table": [[0, 0, 0.0], [0, 40, 0.3], [1, 0, 0.2]],
        "trace": "links.csv",
    }


def link_history(sim: Simulation, steps: int) -> list[bytes]:
    out = []
    for _ in range(steps):
        sim.step()
        out.append(sim.links.tobytes())
    return out


def test_same_seed_same_radio_whatever_else_and_another_seed_another(
    scenario_file: Any, tmp_path: Path
) -> None:
    path = scenario_file(communication=all_options(tmp_path))
    first = link_history(Simulation.from_yaml(path), 30)
    assert first == link_history(Simulation.from_yaml(path), 30)
    assert first != link_history(Simulation.from_yaml(path, seed=99), 30)


def test_radio_options_show_in_metrics_and_replay_recomputes_them(
    scenario_file: Any, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    options = {k: v for k, v in all_options(tmp_path).items() if k != "trace"}
    path = scenario_file(communication=options, steps=30)
    out = tmp_path / "run"
    assert main(["run", str(path), "--out", str(out), "--quiet", "--no-plots"]) == 0
    header = (out / "metrics.csv").read_text(encoding="utf-8").splitlines()[0].split(",")
    assert "connected_to_base" in header and "bytes_sent" not in header
    assert main(["replay", str(out), "--metrics"]) == 0
    assert "identical" in capsys.readouterr().out


def test_a_trace_capacity_bounds_its_pair_from_its_step_on(
    scenario_file: Any, tmp_path: Path
) -> None:
    (tmp_path / "links.csv").write_text("step,a,b,capacity\n5,base,A,300\n", encoding="utf-8")
    path = scenario_file(communication={"model": "disk", "trace": "links.csv"}, steps=20)
    sim = Simulation.from_yaml(path)
    assert sim.network.bounded  # a trace that sets capacities queues what links carry
    sent = []
    for _ in range(20):
        sim.step()
        sent.append((int(sim.comm.traffic.sent[0, 1]), int(sim.comm.traffic.sent[1, 0])))
    assert max(max(pair) for pair in sent[:5]) > 300
    assert max(max(pair) for pair in sent[5:]) <= 300  # each way, from step 5 on


def test_a_trace_saved_by_a_spreadsheet_with_a_byte_order_mark_reads(
    scenario_file: Any, tmp_path: Path
) -> None:
    (tmp_path / "links.csv").write_bytes("\ufeffstep,a,b,up\r\n0,A,B,1\r\n".encode())
    path = scenario_file(communication={"model": "disk", "trace": "links.csv"}, steps=3)
    sim = Simulation.from_yaml(path)
    sim.step()
    assert sim.links[1, 2]


def test_a_trace_path_that_is_a_folder_is_one_paragraph_and_exit_2(
    scenario_file: Any, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "traces").mkdir()
    assert run_validate(scenario_file, trace="traces") == 2
    err = capsys.readouterr().err
    assert "communication.trace" in err and "Traceback" not in err


def test_a_long_correlation_length_is_drawn_coarse_with_the_same_statistics() -> None:
    length = 64.0  # nodes 8 cells apart
    fields = [shadow_field((400, 400), length, np.random.default_rng(s)) for s in range(6)]
    assert np.mean([f.var() for f in fields]) == pytest.approx(1.0, abs=0.12)
    for lag in (16, 32, 64):
        measured = np.mean([lag_correlation(f, lag) for f in fields])
        assert 1 - measured == pytest.approx(1 - correlation(lag, length), abs=0.08)


def test_a_correlation_length_far_beyond_the_map_costs_next_to_nothing() -> None:
    field = shadow_field((300, 500), 100_000.0, np.random.default_rng(1))
    assert field.shape == (300, 500) and np.ptp(field) < 0.05  # one value, nearly


def test_the_built_in_models_with_a_signal_are_the_ones_named_so() -> None:
    from mresim_phys.comms import BUILT_IN, COMM_MODELS
    from mresim_phys.scenario.radio_files import SIGNAL_MODELS

    for name in BUILT_IN:
        assert (name in SIGNAL_MODELS) == hasattr(COMM_MODELS.get(name), "pair_signals")


def test_a_trace_the_csv_module_refuses_is_one_paragraph_and_exit_2(
    scenario_file: Any, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    huge = "x" * 200_000  # beyond the csv module's field limit
    (tmp_path / "links.csv").write_text(f'step,a,b,up\n0,A,B,"{huge}"\n', encoding="utf-8")
    assert run_validate(scenario_file, trace="links.csv") == 2
    err = capsys.readouterr().err
    assert "communication.trace" in err and "not a CSV" in err and "Traceback" not in err
