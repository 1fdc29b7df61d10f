"""Benchmark of phase 6 (communication): all-pairs links and one exchange step.

Prints medians (``time.perf_counter``, wall clock, ms) for the link computation of
every comm model with 8, 16 and 32 agents (plus the base station) at random free
positions of ``maps/office.png`` (800x600); each repeat moves every agent by up
to 3 cells, as a step does. It also times one agent's communication region (129
rays) per model, the whole communication phase (links + delta exchange + counts)
of an 8-robot ``mresim bench``-style run with 'grow' and with 'latest' beliefs, and
the merge of one received transmission into a map (:meth:`Ledger.merge`) for both.

Run from the repository root: ``python benchmarks/bench_comms.py``.
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from mresim_phys.comms import COMM_MODELS, Radios
from mresim_phys.comms.deltas import Cells
from mresim_phys.comms.ledger import Ledger
from mresim_phys.output.bench import team_scenario
from mresim_phys.scenario.load import validate_scenario
from mresim_phys.scenario.readers import load_image_map
from mresim_phys.sim import Simulation
from mresim_phys.world.space import World

ROOT = Path(__file__).resolve().parents[1]
REPEATS = 300
MODELS = {
    "disk": {},
    "line_of_sight": {},
    "path_loss": {},
    "path_loss thickness": {"walls": "thickness"},
}
PHASES = (("disk", "grow"), ("path_loss", "grow"), ("disk", "latest"))  # model, beliefs
MERGE_SHAPE, MERGE_BOX = (600, 800), 120  # the office map; the side of a transmission's box


def median_ms(run: Callable[[], object], repeats: int = REPEATS) -> tuple[float, float]:
    """(median, p90) wall time of ``run`` in ms."""
    times = []
    for _ in range(repeats):
        started = time.perf_counter()
        run()
        times.append((time.perf_counter() - started) * 1e3)
    return statistics.median(times), float(np.percentile(times, 90))


def free_points(occupied: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` random cell centres of free cells."""
    rows, cols = np.nonzero(~occupied)
    pick = rng.choice(len(rows), size=n, replace=False)
    return np.column_stack([cols[pick] + 0.5, rows[pick] + 0.5])


def jitter(points: np.ndarray, rng: np.random.Generator, shape: tuple[int, int]) -> np.ndarray:
    """Every point moved by up to 3 cells, kept inside the map."""
    moved = points + rng.uniform(-3, 3, size=points.shape)
    return np.clip(moved, 0.5, np.array([shape[1], shape[0]]) - 0.5)


def time_links(model: object, points: np.ndarray, world: World, rng: np.random.Generator) -> None:
    """Print the median link time of ``model`` for agents starting at ``points``."""
    ranges = np.full(len(points), 150.0)
    moving = [points]

    def step() -> object:
        moving[0] = jitter(moving[0], rng, world.shape)
        return model.links(Radios.of(moving[0], ranges), world)  # type: ignore[attr-defined]

    step()  # compile
    median, p90 = median_ms(step)
    label = f"{model.name} {getattr(model.params, 'walls', '')}".strip()  # type: ignore[attr-defined]
    agents = len(points) - 1
    print(f"links {label:20s} {agents:2d} agents + base: median {median:6.3f} ms  p90 {p90:6.3f}")


def bench_links(world: World, agents: int, rng: np.random.Generator) -> None:
    """Median link time per model for ``agents`` robots plus the base."""
    points = free_points(world.occupied, agents + 1, rng)
    for label, params in MODELS.items():
        cls = COMM_MODELS.get(label.split()[0])
        time_links(cls(cls.Params.model_validate(params)), points, world, rng)


def bench_regions(world: World, rng: np.random.Generator) -> None:
    """Median time of one agent's 129-ray communication region per model."""
    points = free_points(world.occupied, 9, rng)
    angles = np.linspace(0, 2 * np.pi, 129, endpoint=False)
    radios = Radios.of(points, np.full(9, 150.0))
    for label, params in MODELS.items():
        cls = COMM_MODELS.get(label.split()[0])
        model = cls(cls.Params.model_validate(params))
        model.reach(radios, 0, angles, world)
        median, p90 = median_ms(lambda m=model: m.reach(radios, 0, angles, world))
        print(f"region {label:19s} 129 rays: median {median:6.3f} ms  p90 {p90:6.3f}")


def bench_phase() -> None:
    """The communication phase of an 8-robot office run (after 60 warm-up steps)."""
    for model, belief in PHASES:
        data = team_scenario(8, ROOT / "maps" / "office.png", 200)
        simulation = {**data["simulation"], "belief": belief}
        sim = Simulation(
            validate_scenario({**data, "communication": model, "simulation": simulation})
        )
        for _ in range(60):
            sim.step()
        times = []
        for _ in range(100):
            before = sim.phase_times["communication"]
            sim.step()
            times.append((sim.phase_times["communication"] - before) * 1e3)
        print(
            f"phase {model:10s} {belief:6s} 8 robots: communication median"
            f" {statistics.median(times):.3f} ms p90 {np.percentile(times, 90):.3f} ms"
            " (links + delta exchange + counts)"
        )


def transmission(rng: np.random.Generator) -> tuple[Cells, np.ndarray]:
    """Half the cells of a box, in raster order, as one transmission carries them (their
    codes and observation steps), and the receiver's codes of the map."""
    rows, cols = MERGE_SHAPE
    box = np.add.outer(np.arange(200, 200 + MERGE_BOX) * cols, np.arange(300, 300 + MERGE_BOX))
    flat = np.sort(rng.choice(box.ravel(), box.size // 2, replace=False))
    states = np.array([0, 1, 2, 5, 6], np.uint8)  # unknown, free, obstacle; with safe space
    theirs, seen = rng.choice(states, flat.size), rng.integers(0, 60, flat.size, np.int32)
    return Cells(flat, theirs, seen), rng.choice(states, (rows, cols))


def bench_merge(rng: np.random.Generator) -> None:
    """Median time of :meth:`Ledger.merge` of one transmission (a fresh receiver each time)."""
    cells, codes = transmission(rng)
    observed = rng.integers(0, 60, MERGE_SHAPE).astype(np.int32)
    for belief in ("grow", "latest"):
        latest = belief == "latest"
        message = cells if latest else cells._replace(seen=None)
        times = []
        for _ in range(REPEATS + 1):  # the first one compiles
            ledger = Ledger(MERGE_SHAPE, 2, latest=latest)
            ledger.copies[1][:] = codes
            grids = (codes & 3, (codes & 4) != 0)
            steps = observed.copy() if latest else None
            started = time.perf_counter()
            ledger.merge(1, message, grids, 60, 0, steps)
            times.append((time.perf_counter() - started) * 1e3)
        median, p90 = statistics.median(times[1:]), float(np.percentile(times[1:], 90))
        print(f"merge {belief:6s} {cells.flat.size} cells: median {median:7.4f} ms  p90 {p90:7.4f}")


def main() -> None:
    world = World(load_image_map(ROOT / "maps" / "office.png").occupied, [])
    rng = np.random.default_rng(0)
    for agents in (8, 16, 32):
        bench_links(world, agents, rng)
    bench_regions(world, rng)
    bench_merge(rng)
    bench_phase()


if __name__ == "__main__":
    main()
