"""Robots on threads (mresim_phys/parallel.py): a run with threads gives the serial run.

Every comparison is exact: the step records (floats as their bits), every robot's pose,
path and belief grid, and in a separate process the metrics.csv bytes.
"""

from __future__ import annotations

import random
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import mresim_phys.parallel as parallel
import mresim_phys.sensing_phase as sensing_phase
from mresim_phys.cli import main
from mresim_phys.knowledge.scanfold import ScanQueue
from mresim_phys.parallel import RobotPool, thread_count, usable_cores
from mresim_phys.planning.topocache import MapCache
from mresim_phys.sim import Simulation
from mresim_phys.world.space import World

ROOT = Path(__file__).resolve().parent.parent
SCENARIOS = ROOT / "scenarios"


def fingerprint(sim: Simulation) -> tuple[Any, ...]:
    """What must not depend on the thread count: the record and every robot's state."""
    robots = tuple(
        (r.position, r.heading, r.distance, r.status, r.path.tobytes(), r.belief.tobytes())
        for r in sim.robots
    )
    return sim.record, robots, sim.base.belief.tobytes(), sim.coverage.count


def trace(path: Path, steps: int, **overrides: Any) -> list[tuple[Any, ...]]:
    """The fingerprint after every step of the scenario at ``path``."""
    sim = Simulation.from_yaml(path, steps=steps, **overrides)
    prints = [fingerprint(sim)]
    while not sim.finished():
        sim.step()
        prints.append(fingerprint(sim))
    return prints


@pytest.mark.parametrize("seed", [1, 2, 3])
@pytest.mark.parametrize("robots_block", [False, True])
def test_two_threads_give_the_serial_run(seed: int, robots_block: bool) -> None:
    """Four robots on the rooms map, two of them failing on the way (events at 30, 60)."""
    path = SCENARIOS / "03_rooms_failures.yaml"
    serial = trace(path, 90, seed=seed, **{"simulation.robots_block": robots_block})
    threaded = trace(path, 90, seed=seed, simulation={"robots_block": robots_block, "threads": 2})
    assert threaded == serial


def test_planners_on_threads_give_the_serial_run() -> None:
    """A*, JPS and two topological planners (their shared map cache) on threads."""
    path = SCENARIOS / "09_planners.yaml"
    assert trace(path, 40, **{"simulation.threads": 2}) == trace(path, 40)


def test_eight_robots_at_the_originals_settings_on_threads() -> None:
    path = SCENARIOS / "11_library_8_robots.yaml"
    assert trace(path, 25, **{"simulation.threads": "auto"}) == trace(path, 25)


def slowed(
    real: Callable[..., Any], jitter: random.Random, threads_seen: set[int]
) -> Callable[..., Any]:
    """``real`` taking a random extra time, noting the threads that called it."""

    def slow(*args: Any, **kwargs: Any) -> Any:
        threads_seen.add(threading.get_ident())
        time.sleep(jitter.random() * 2e-4)
        return real(*args, **kwargs)

    return slow


def test_the_threads_timing_does_not_matter(monkeypatch: pytest.MonkeyPatch) -> None:
    """Scans that take random extra time (so robots finish in ever other orders) change
    nothing: every shared effect is applied in robot order."""
    path = SCENARIOS / "03_rooms_failures.yaml"
    serial = trace(path, 40, **{"simulation.robots_block": True})
    jitter = random.Random(7)
    threads_seen: set[int] = set()
    for name in ("scan", "scan_into_map"):  # noisy and noiseless scans
        monkeypatch.setattr(
            sensing_phase, name, slowed(getattr(sensing_phase, name), jitter, threads_seen)
        )
    # the scans a robot's turn holds back (ScanQueue) fold together
    monkeypatch.setattr(ScanQueue, "fold", slowed(ScanQueue.fold, jitter, threads_seen))
    threaded = trace(path, 40, simulation={"robots_block": True, "threads": 3})
    assert threaded == serial
    assert len(threads_seen) > 1  # the robots really ran on several threads


def test_threads_in_another_process_write_the_same_metrics(tmp_path: Path) -> None:
    path = SCENARIOS / "03_rooms_failures.yaml"
    flags = ["--steps", "70", "--quiet", "--no-plots", "--no-log", "--overwrite"]
    assert main(["run", str(path), "--out", str(tmp_path / "serial"), *flags]) == 0
    command = [sys.executable, "-m", "mresim_phys.cli", "run", str(path), "--threads", "2"]
    done = subprocess.run(
        [*command, "--out", str(tmp_path / "threads"), *flags],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    serial = (tmp_path / "serial" / "metrics.csv").read_bytes()
    assert (tmp_path / "threads" / "metrics.csv").read_bytes() == serial


def test_thread_counts() -> None:
    assert thread_count(1, 8) == 1
    assert thread_count(4, 3) == 3  # never more threads than robots
    assert thread_count(4, 0) == 1
    assert thread_count("auto", 64) == min(usable_cores(), 64)
    assert thread_count("auto", 1) == 1


def test_the_pool_keeps_task_order_and_raises_the_first_error() -> None:
    pool = RobotPool(3)

    def task(k: int) -> Callable[[], int]:
        def run() -> int:
            time.sleep(0.002 * (5 - k))  # later tasks finish first
            if k in (2, 4):
                raise ValueError(f"task {k}")
            return k

        return run

    assert pool.run([task(k) for k in (0, 1, 3)]) == [0, 1, 3]
    with pytest.raises(ValueError, match="task 2"):
        pool.run([task(k) for k in range(5)])
    pool.close()
    assert pool.run([task(0), task(1)]) == [0, 1]  # a closed pool starts new threads
    pool.close()


def test_heavy_tasks_start_first_and_results_keep_the_task_order() -> None:
    started: list[int] = []
    lock = threading.Lock()

    def task(k: int) -> Callable[[], int]:
        def run() -> int:
            with lock:
                started.append(k)
            time.sleep(0.01)
            return k

        return run

    pool = RobotPool(1 + 1)
    heavy = [False, False, True, False, True]
    assert pool.run([task(k) for k in range(5)], heavy) == [0, 1, 2, 3, 4]
    assert set(started[:2]) == {2, 4}  # the two threads took the heavy ones first
    assert started[2:] == [0, 1, 3]
    pool.close()


def test_threads_hand_the_gil_over_often_while_tasks_run_and_only_then() -> None:
    """A task returning from a compiled kernel waits for the GIL at most one short turn."""
    before = sys.getswitchinterval()
    pool = RobotPool(2)
    seen = pool.run([sys.getswitchinterval, sys.getswitchinterval])
    assert seen == pytest.approx([parallel.SWITCH_INTERVAL] * 2) and max(seen) < before
    with pytest.raises(ZeroDivisionError):
        pool.run([sys.getswitchinterval, lambda: 1 / 0])
    assert sys.getswitchinterval() == before  # restored, also after a failing task
    assert RobotPool(1).run([sys.getswitchinterval]) == [before]  # serial: untouched
    pool.close()


def test_an_interrupted_run_leaves_no_task_running() -> None:
    """A KeyboardInterrupt while the robots run (it reaches the calling thread, which runs
    tasks too): the queued tasks never start, the workers' running ones finish before it
    propagates (nothing changes a robot after the step is given up)."""
    started: list[int] = []
    finished: list[int] = []
    caller = threading.get_ident()

    def task(k: int) -> Callable[[], int]:
        def run() -> int:
            started.append(k)
            time.sleep(0.02)
            if threading.get_ident() == caller:
                raise KeyboardInterrupt  # Ctrl-C arrives in the calling thread
            finished.append(k)
            return k

        return run

    pool = RobotPool(3)
    with pytest.raises(KeyboardInterrupt):
        pool.run([task(k) for k in range(9)])
    on_workers = len(started) - 1
    assert len(finished) == on_workers and len(started) < 9
    time.sleep(0.05)
    assert len(started) == on_workers + 1 < 9  # nothing started later
    assert pool.run([lambda: 1, lambda: 2, lambda: 3]) == [1, 2, 3]  # the pool serves on
    pool.close()


def test_world_queries_from_several_threads_match_one_thread(rooms: np.ndarray) -> None:
    """Chipmunk's queries lock the Space by a counter: World serialises them."""
    world = World(rooms, [1.0, 1.5])
    world.place_robots([(20.0, 30.0), (60.0, 30.0)])
    rng = np.random.default_rng(3)
    starts, ends = rng.uniform(3, 77, (300, 2)), rng.uniform(3, 77, (300, 2))
    radii = rng.uniform(0, 2, 300)
    moves = [(tuple(a), tuple(b), r) for a, b, r in zip(starts, ends, radii, strict=True)]
    shape_filter = world.query_filter(None, robots_block=True)

    def answers() -> list[Any]:
        return [world.first_hit(a, b, r, shape_filter) for a, b, r in moves]

    expected = answers()
    results: list[list[Any]] = []
    workers = [threading.Thread(target=lambda: results.append(answers())) for _ in range(4)]
    for worker in workers:
        worker.start()
    for worker in workers:
        worker.join()
    assert results == [expected] * 4
    world.place_robots([(22.0, 30.0), (60.0, 32.0)])  # the Space is not left locked
    assert world.bodies[0].position == (22.0, 30.0)


def test_the_shared_map_cache_serves_several_threads(rooms: np.ndarray) -> None:
    """Threads asking a small cache for more maps than it keeps get the serial builds."""
    masks = [~rooms, ~np.roll(rooms, 3, axis=1), ~np.roll(rooms, 5, axis=0)]
    expected = [MapCache().get(m, 6).labels for m in masks]
    cache, failures = MapCache(capacity=2), []

    def ask() -> None:
        for k in range(30):
            labels = cache.get(masks[k % 3], 6).labels
            if not np.array_equal(labels, expected[k % 3]):
                failures.append(k)

    workers = [threading.Thread(target=ask) for _ in range(4)]
    interval = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)  # threads take turns between almost any two bytecodes
    try:
        for worker in workers:
            worker.start()
        for worker in workers:
            worker.join()
    finally:
        sys.setswitchinterval(interval)
    assert not failures and len(cache._maps) == 2
