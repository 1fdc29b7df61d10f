"""Benchmark of phase 6 (communication): all-pairs links and one exchange step.

Prints medians (``time.perf_counter``, wall clock, ms) for the link computation of
every comm model with 8, 16 and 32 agents (plus the base station) at random free
positions of ``maps/office.png`` (800x600); each repeat moves every agent by up
to 3 cells, as a step does. It also times one agent's communication region (129
rays) per model, and the whole communication phase (links + delta exchange + counts)
of an 8-robot ``mresim bench``-style run.

Run from the repository root: ``python benchmarks/bench_comms.py``.
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from mresim_phys.comms import COMM_MODELS, Radios
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
    for model in ("disk", "path_loss"):
        data = team_scenario(8, ROOT / "maps" / "office.png", 200)
        sim = Simulation(validate_scenario({**data, "communication": model}))
        for _ in range(60):
            sim.step()
        times = []
        for _ in range(100):
            before = sim.phase_times["communication"]
            sim.step()
            times.append((sim.phase_times["communication"] - before) * 1e3)
        print(
            f"phase {model:10s} 8 robots: communication median {statistics.median(times):.3f} ms"
            f" p90 {np.percentile(times, 90):.3f} ms (links + delta exchange + counts)"
        )


def main() -> None:
    world = World(load_image_map(ROOT / "maps" / "office.png").occupied, [])
    rng = np.random.default_rng(0)
    for agents in (8, 16, 32):
        bench_links(world, agents, rng)
    bench_regions(world, rng)
    bench_phase()


if __name__ == "__main__":
    main()
