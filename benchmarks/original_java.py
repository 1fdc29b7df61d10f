"""The Java original's side of ``bench_against.py --original``: is a built tree there, which
team files it has, and one timed run of it through the headless driver.

The driver (``HeadlessDriver.java`` with ``build.sh`` and ``run.sh``, outside this
repository: ``DRIVER``, its README says how to build) runs the unmodified original under
Xvfb, calling its ``simulationCycle`` back to back with ``System.out`` sent to a null
stream, and prints a line per cycle: ``cycle wall_ms cpu_ms gui_ms joint base explored
known_at_base``. A run's figures are the medians of ``wall_ms`` and ``cpu_ms`` (process CPU,
all threads) over the timed cycles, the warm-up cycles skipped.
"""

from __future__ import annotations

import shutil
import statistics
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

DRIVER = Path("/work/shared/original")  # build.sh, run.sh, HeadlessDriver.java, README.md
DRIVER_CLASS = Path("build/exploration/HeadlessDriver.class")
MAP = "environments/library.png"


@dataclass(frozen=True)
class CycleTimes:
    """One run of the original: median ms per cycle over the timed cycles."""

    wall_ms: float
    cpu_ms: float


def require_built(tree: Path, driver: Path, named_by: str, script: str) -> None:
    """Exit with status 2 and one paragraph on what is missing unless ``tree`` is a built
    original and its driver, ``xvfb-run`` and ``java`` are there."""
    missing = []
    if not tree.is_dir():
        missing.append(f"there is no folder {tree}")
    elif not (tree / DRIVER_CLASS).is_file():
        missing.append(f"{tree} is not built (no {DRIVER_CLASS})")
    if not (driver / "run.sh").is_file():
        missing.append(f"the headless driver's run.sh is not in {driver} (give --driver)")
    missing += [
        f"{tool} is not installed" for tool in ("xvfb-run", "java") if not shutil.which(tool)
    ]
    if missing:
        home = driver if (driver / "README.md").is_file() else DRIVER
        print(
            f"{script}: cannot time the Java original named by {named_by} ({tree}): "
            f"{'; '.join(missing)}. Extract v-spirin/MRESim into a folder outside this"
            " repository (`git --git-dir=MIRROR archive HEAD | tar -x -C TREE`), install"
            " Xvfb (`apt-get install -y xvfb`) and a JDK, and build it with the driver"
            f" (`sh {home}/build.sh TREE`), as {home}/README.md describes; then give"
            " --original TREE (or set MRESIM_ORIGINAL).",
            file=sys.stderr,
        )
        raise SystemExit(2)


def team_file(tree: Path, robots: int) -> Path | None:
    """The original's library team of ``robots`` explorers, if it ships one."""
    path = tree / "config" / f"{robots}robots_library"
    return path if path.is_file() else None


def time_original(
    tree: Path, driver: Path, team: Path, seed: int, warmup: int, steps: int
) -> CycleTimes:
    """Run the original for ``warmup + steps`` cycles of ``team`` on its library and time it
    (:func:`timed_cycles`); SystemExit with the driver's last words if it fails."""
    command = [
        "sh", str(driver / "run.sh"), str(tree), "--team", str(team.relative_to(tree)),
        "--map", MAP, "--seed", str(seed), "--cycles", str(warmup + steps),
    ]  # fmt: skip
    out = subprocess.run(command, capture_output=True, text=True, check=False)
    try:
        wall, cpu = timed_cycles(out.stdout, warmup, steps)
    except ValueError as exc:
        tail = "\n".join(out.stderr.strip().splitlines()[-15:])
        raise SystemExit(
            f"the original's run failed (exit {out.returncode}, {exc}): {' '.join(command)}\n{tail}"
        ) from None
    return CycleTimes(statistics.median(wall), statistics.median(cpu))


def timed_cycles(text: str, warmup: int, steps: int) -> tuple[list[float], list[float]]:
    """``wall_ms`` and ``cpu_ms`` of cycles ``warmup + 1`` to ``warmup + steps`` in the
    driver's output; ValueError if some are missing.

    >>> timed_cycles("# head\\ncycle wall_ms cpu_ms\\n1 900.0 950 1\\n2 400.5 410 1\\n", 1, 1)
    ([400.5], [410.0])
    """
    wall, cpu = [], []
    for line in text.splitlines():
        fields = line.split()
        if len(fields) >= 3 and fields[0].isdigit() and warmup < int(fields[0]) <= warmup + steps:
            wall.append(float(fields[1]))
            cpu.append(float(fields[2]))
    if len(wall) != steps:
        raise ValueError(f"{len(wall)} of the {steps} timed cycles printed")
    return wall, cpu
