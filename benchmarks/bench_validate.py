"""Benchmark of ``mresim validate``: wall time and modules imported, this tree against REV.

Each round runs ``python -X importtime -m mresim_phys.launch validate SCENARIO`` once per
build for every scenario, each in a fresh process, the builds alternating so that a busy
spell of a shared machine hits both alike (REV is checked out into a temporary git
worktree). It prints, per build, the median wall time over rounds and scenarios, the
modules imported (the lines of ``-X importtime``) and whether numba, pymunk or cv2 were
among them; then the ratio of the medians.

Run from the repository root: ``python benchmarks/bench_validate.py REV [--rounds 5]
[SCENARIO ...]`` (default: every shipped scenario).
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from worktree import checked_out

ROOT = Path(__file__).resolve().parent.parent
HEAVY = ("numba", "pymunk", "cv2")


def validate_once(tree: Path, scenario: Path) -> tuple[float, list[str]]:
    """(wall seconds, modules imported) of one ``mresim validate`` with the code of ``tree``."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    started = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-X", "importtime", "-m", "mresim_phys.launch", "validate", str(scenario)],
        cwd=tempfile.gettempdir(),  # not the repository: PYTHONPATH decides the build
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    seconds = time.perf_counter() - started
    lines = [ln for ln in done.stderr.splitlines() if ln.startswith("import time:")]
    modules = [ln.rsplit("|", 1)[-1].strip() for ln in lines[1:]]  # the first is a header
    return seconds, modules


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("rev", help="the commit to compare with (e.g. HEAD~5)")
    parser.add_argument("scenarios", nargs="*", type=Path, help="default: scenarios/*.yaml")
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()
    scenarios = [p.resolve() for p in args.scenarios] or sorted((ROOT / "scenarios").glob("*.yaml"))
    with checked_out(ROOT, args.rev, "bench_validate.py") as old:
        compare(old, scenarios, args)


def compare(old: Path, scenarios: list[Path], args: argparse.Namespace) -> None:
    """Alternate the builds over rounds and scenarios; print medians, modules and ratio."""
    seconds: dict[str, list[float]] = {"before": [], "now": []}
    modules: dict[str, list[int]] = {"before": [], "now": []}
    heavy: dict[str, set[str]] = {"before": set(), "now": set()}
    for k in range(args.rounds):
        for scenario in scenarios:
            builds = [("before", old), ("now", ROOT)]
            for name, tree in builds if k % 2 == 0 else builds[::-1]:
                took, names = validate_once(tree, scenario)
                seconds[name].append(took)
                modules[name].append(len(names))
                heavy[name] |= {m.split(".")[0] for m in names} & set(HEAVY)
    print(f"mresim validate, {len(scenarios)} scenarios x {args.rounds} rounds")
    print(" build    median s   modules (median)   numba/pymunk/cv2 imported")
    for name in ("before", "now"):
        found = ", ".join(sorted(heavy[name])) or "none"
        print(
            f" {name:<7} {statistics.median(seconds[name]):9.2f}"
            f" {statistics.median(modules[name]):18.0f}   {found}"
        )
    ratio = statistics.median(seconds["now"]) / statistics.median(seconds["before"])
    print(f" now/before {ratio:.2f}")


if __name__ == "__main__":
    main()
