"""Golden runs: every shipped scenario's metrics.csv and summary.json, kept byte for byte.

A refactor must not move results. ``python tools/golden.py record`` runs every
``scenarios/*.yaml`` to its end and stores its ``metrics.csv`` (gzip) and its
``summary.json`` without wall-clock fields under ``tests/golden/<scenario>/``;
``python tools/golden.py check`` runs them again and reports every difference
(``tests/test_golden.py`` runs the same check in the suite). Record again only on
purpose, in a commit that says why the results moved.
"""

from __future__ import annotations

import argparse
import gzip
import json
import sys
import tempfile
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
SCENARIOS = sorted((ROOT / "scenarios").glob("*.yaml"))
GOLDEN = ROOT / "tests" / "golden"
WALL_CLOCK = ("wall_time_s", "steps_per_second")


def run_scenario(path: Path, out_dir: Path) -> Path:
    """Run ``path`` to its end as ``mresim run --no-plots --quiet`` does; return the run folder."""
    from mresim_phys.cli import main

    code = main(["run", str(path), "--out", str(out_dir), "--quiet", "--no-plots"])
    if code != 0:
        raise RuntimeError(f"{path.name}: mresim run exited with {code}")
    return out_dir


def summary_text(run_dir: Path) -> str:
    """summary.json without its wall-clock fields, as stable text."""
    summary: dict[str, Any] = json.loads((run_dir / "summary.json").read_text(encoding="utf-8"))
    for key in WALL_CLOCK:
        summary.pop(key, None)
    return json.dumps(summary, indent=2) + "\n"


def record(path: Path, run_dir: Path) -> None:
    """Store ``run_dir``'s results as the golden results of scenario ``path``."""
    folder = GOLDEN / path.stem
    folder.mkdir(parents=True, exist_ok=True)
    metrics = (run_dir / "metrics.csv").read_bytes()
    with gzip.GzipFile(folder / "metrics.csv.gz", "wb", mtime=0) as handle:
        handle.write(metrics)
    (folder / "summary.json").write_text(summary_text(run_dir), encoding="utf-8")


def first_difference(expected: bytes, actual: bytes) -> str:
    """Where two metrics files first differ, as a readable line pair."""
    pairs = zip(expected.splitlines(), actual.splitlines(), strict=False)
    for number, (a, b) in enumerate(pairs, 1):
        if a != b:
            return f"line {number}:\n  golden: {a.decode()}\n  now:    {b.decode()}"
    return f"lengths differ: {len(expected.splitlines())} vs {len(actual.splitlines())} lines"


def compare(path: Path, run_dir: Path) -> list[str]:
    """Differences between ``run_dir`` and the golden results of ``path`` (empty: identical)."""
    folder = GOLDEN / path.stem
    if not folder.is_dir():
        return [f"{path.stem}: no golden results (run `python tools/golden.py record`)"]
    problems = []
    expected = gzip.decompress((folder / "metrics.csv.gz").read_bytes())
    actual = (run_dir / "metrics.csv").read_bytes()
    if expected != actual:
        problems.append(f"{path.stem}: metrics.csv differs at {first_difference(expected, actual)}")
    if (folder / "summary.json").read_text(encoding="utf-8") != summary_text(run_dir):
        problems.append(f"{path.stem}: summary.json differs")
    return problems


def main(argv: list[str] | None = None) -> int:
    """``record`` or ``check`` every shipped scenario (or those named)."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("action", choices=("record", "check"))
    parser.add_argument("names", nargs="*", help="scenario stems (default: all)")
    args = parser.parse_args(argv)
    chosen = [p for p in SCENARIOS if not args.names or p.stem in args.names]
    problems: list[str] = []
    with tempfile.TemporaryDirectory() as tmp:
        for path in chosen:
            run_dir = run_scenario(path, Path(tmp) / path.stem)
            if args.action == "record":
                record(path, run_dir)
                print(f"recorded {path.stem}")
            else:
                found = compare(path, run_dir)
                problems += found
                print(f"{path.stem}: {'DIFFERENT' if found else 'identical'}")
    for line in problems:
        print(line, file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))
    sys.exit(main())
