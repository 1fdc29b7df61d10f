"""Views (phase 8), raster stage: the numba label kernels against a plain numpy reference."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from mresim_phys import Simulation
from mresim_phys.knowledge.frontiers import frontier_mask
from mresim_phys.render import ROBOT_LAYERS, LayerSpec, Renderer, Style, parse_layers
from mresim_phys.render.raster import LabelGrids, colour_labels, known_box, packed_colours
from mresim_phys.render.style import DEFAULT_STYLE
from mresim_phys.snapshot import AgentSnapshot, Snapshot, read_only
from mresim_phys.types import FREE, OCCUPIED, UNKNOWN

N_COLOURS = len(Style().palette)


def reference_labels(snap: Snapshot, layers: LayerSpec, n: int) -> np.ndarray:
    """The label grid as the numpy renderer computed it (bounding box + 1 per robot)."""
    on = layers.global_layers
    team = np.zeros(snap.truth.shape, np.uint8)
    for robot in snap.robots if "team_known" in on else ():
        team |= robot.belief
    label = team & FREE
    if "known_at_base" in on:
        label = np.maximum(label, (snap.base.belief == FREE) * np.uint8(2))
    if "walls" in on:
        label = np.maximum(label, snap.truth * np.uint8(3))
    tint = np.zeros_like(label)
    for i, robot in enumerate(snap.robots):
        mine, rows, cols = layers.for_agent(robot.name), *np.nonzero(robot.belief)
        if len(rows):
            box = (
                slice(max(rows.min() - 1, 0), rows.max() + 2),
                slice(max(cols.min() - 1, 0), cols.max() + 2),
            )
            belief, lab, ti = robot.belief[box], label[box], tint[box]
            if "free_space" in mine:
                ti[:] = np.maximum(ti, (belief == FREE) * np.uint8(1 + i % n))
            if "safe_space" in mine:
                ti[:] = np.maximum(ti, robot.safe[box] * np.uint8(1 + n + i % n))
            if "frontiers" in mine:
                lab[:] = np.maximum(lab, frontier_mask(belief) * np.uint8(5))
        if "skeleton" in mine and robot.skeleton is not None:
            label = np.maximum(label, robot.skeleton * np.uint8(4))
    return label + 6 * tint


def random_belief(rng: np.random.Generator, shape: tuple[int, int]) -> np.ndarray:
    """Unknown, with a few random known rectangles of free cells with walls in them."""
    belief = np.zeros(shape, np.uint8)
    for _ in range(rng.integers(0, 4)):
        r0, c0 = rng.integers(0, shape[0]), rng.integers(0, shape[1])
        r1, c1 = r0 + rng.integers(1, shape[0] // 2 + 2), c0 + rng.integers(1, shape[1] // 2 + 2)
        block = belief[r0:r1, c0:c1]
        block[:] = np.where(rng.random(block.shape) < 0.1, OCCUPIED, FREE)
        block[rng.random(block.shape) < 0.05] = UNKNOWN
    return belief


def random_snapshot(rng: np.random.Generator, shape: tuple[int, int], n: int) -> Snapshot:
    def agent(name: str, kind: str) -> AgentSnapshot:
        belief = random_belief(rng, shape)
        safe = (rng.random(shape) < 0.2) & (belief != UNKNOWN)
        skeleton = rng.random(shape) < 0.05 if rng.random() < 0.5 else None
        return AgentSnapshot(
            name, kind, (1.0, 1.0), 0.0, 1.0, "active", kind, 0.0, read_only(belief), safe,
            skeleton=skeleton,
        )  # fmt: skip

    agents = (agent("base", "base"), *(agent(f"R{i}", "robot") for i in range(n)))
    truth = rng.random(shape) < 0.1
    return Snapshot(1, 0.0, 0.0, n, truth, agents, np.zeros((n + 1, n + 1), bool))


def random_layers(rng: np.random.Generator, names: list[str]) -> LayerSpec:
    def some(layers: tuple[str, ...]) -> frozenset[str]:
        return frozenset(name for name in layers if rng.random() < 0.6)

    globals_ = some(("walls", "unexplored", "team_known", "known_at_base"))
    per_robot = {name: some(ROBOT_LAYERS) for name in names if rng.random() < 0.5}
    return LayerSpec(globals_, some(ROBOT_LAYERS), per_robot)


@pytest.mark.parametrize("shape", [(1, 1), (2, 7), (9, 1), (23, 31), (64, 48)])
def test_labels_equal_the_numpy_reference(shape: tuple[int, int]) -> None:
    rng = np.random.default_rng(sum(shape))
    grids = LabelGrids(shape)
    for trial in range(25):
        snap = random_snapshot(rng, shape, n=int(rng.integers(0, 12)))
        layers = random_layers(rng, [r.name for r in snap.robots])
        expected = reference_labels(snap, layers, N_COLOURS)
        assert np.array_equal(grids.labels(snap, layers, N_COLOURS), expected), trial


def test_frontier_cells_at_the_grid_edges() -> None:
    belief = np.full((5, 6), FREE, np.uint8)
    belief[0, 5] = belief[4, 0] = UNKNOWN
    belief[2, 2] = OCCUPIED
    snap = random_snapshot(np.random.default_rng(0), (5, 6), n=1)
    robot = AgentSnapshot("R0", "robot", (1.0, 1.0), 0.0, 1.0, "active", "robot", 0.0,
                          belief, np.zeros((5, 6), bool))  # fmt: skip
    snap = Snapshot(1, 0.0, 0.0, 1, np.zeros((5, 6), bool), (snap.base, robot), np.eye(2) > 1)
    label = LabelGrids((5, 6)).labels(snap, LayerSpec(frozenset(), frozenset({"frontiers"})), 10)
    assert np.array_equal(label == 5, frontier_mask(belief))
    assert (label == 5).sum() == 6  # 3 cells around each unknown corner, none outside


@pytest.mark.parametrize("shape", [(1, 1), (3, 8), (40, 30)])
def test_known_box(shape: tuple[int, int]) -> None:
    rng = np.random.default_rng(1)
    for _ in range(20):
        belief = (rng.random(shape) < rng.choice([0.0, 0.01, 0.3])).astype(np.uint8)
        rows, cols = np.nonzero(belief)
        if len(rows):
            expected = (rows.min(), rows.max() + 1, cols.min(), cols.max() + 1)
        else:
            expected = (0, 0, 0, 0)
        assert known_box(belief) == expected


def test_colouring_pads_with_the_blank_colour() -> None:
    renderer = Renderer((3, 5), LayerSpec())
    table = packed_colours(renderer._lut)
    label = np.array([[0, 1, 2, 3, 5], [6, 7, 12, 1, 0], [3, 3, 3, 3, 3]], np.uint8)
    image = np.zeros((4, 6, 3), np.uint8)
    colour_labels(label, table, image)
    assert np.array_equal(image[:3, :5], renderer._lut[label, 0])
    assert (image[3] == renderer._lut[0, 0]).all() and (image[:, 5] == renderer._lut[0, 0]).all()


def test_the_ghost_walls_layer_paints_walls_a_map_holds_where_the_truth_is_free(
    scenario_file: Callable[..., Path],
) -> None:
    sim = Simulation.from_yaml(scenario_file())
    robot = sim.robots[0]
    robot.belief[10:20, 20:22] = OCCUPIED  # free in the truth: a ghost wall
    robot.belief[0:2, 0:10] = OCCUPIED  # the outer wall: a true wall, no ghost
    snap = sim.snapshot()
    shaded = Renderer(snap.truth.shape, parse_layers("default,ghost_walls"), 8).render(snap)
    plain = Renderer(snap.truth.shape, parse_layers("default"), 8).render(snap)
    ghost, wall = np.s_[84:156, 162:174], np.s_[2:14, 8:72]  # 8 px per cell
    assert np.array_equal(shaded[wall], plain[wall])
    colour = np.array(DEFAULT_STYLE.ghost_wall)
    assert (np.abs(shaded[ghost].astype(int) - colour).sum(axis=-1) < 10).mean() > 0.9
    assert not (np.abs(plain[ghost].astype(int) - colour).sum(axis=-1) < 10).any()
