"""Interrupt trials: SIGINT and SIGTERM sent to real ``mresim run`` processes lose nothing.

``python tools/interrupt_trials.py [--trials 20] [--jobs 2]`` runs, for every signal
(SIGINT, SIGTERM) and progress bar (on, off), ``--trials`` runs of ``python -m
mresim_phys.cli run`` on a long random-walk scenario: it waits until the run's metrics rows
reach the disk, waits a random fraction of a second more (to hit every phase of a step),
sends the signal (and in every other trial a second one 0.05 s later) and checks what the
run left (:func:`problems`): exit status 128 + the signal, ``summary.json`` with
``stop_reason`` ``interrupted`` and the signal's name, as many ``metrics.csv`` rows as
logged steps (summary steps + 1, log closed), ``mresim replay RUN --metrics`` identical,
no traceback on stderr. Prints the counts per combination; exits 1 on any loss.
``tests/test_interrupts.py`` runs one trial of each combination with :func:`trial`.
"""

from __future__ import annotations

import argparse
import json
import random
import signal
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parent.parent
MAP = ROOT / "maps" / "small_rooms.png"
STARTUP_TIMEOUT_S = 120.0  # imports and numba's cache on a loaded 2-core machine
SECOND_SIGNAL_S = 0.05


def long_scenario(folder: Path) -> Path:
    """A random-walk run that only a signal ends (no step cap in reach, no stop rule)."""
    data = {
        "name": "interrupt-trial",
        "seed": 1,
        "steps": 1_000_000,
        "stop": {"stalled_for": None},
        "map": {"image": str(MAP), "resolution": 0.1},
        "base_station": {"position": [20, 60], "comm_range": 40},
        "team": {"speed": 3, "radius": 2, "sensor": {"range": 60}, "comm_range": 40},
        "robots": [
            {"name": "A", "start": [66, 52], "strategy": "random_walk"},
            {"name": "B", "start": [66, 68], "strategy": "random_walk"},
        ],
    }
    path = folder / "long.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return path


@dataclass
class Trial:
    """One interrupted run and what went wrong with it (``lost``: nothing if empty)."""

    signal: str
    bar: bool
    double: bool
    lost: list[str] = field(default_factory=list)


def ctrl_c_reaches_children() -> None:
    """Let SIGINT reach the runs: a process started in the background of a shell ignores it,
    and so would its children; an ignored signal stays ignored in ``mresim run`` (by design).
    Call from the main thread before starting trials."""
    if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)


def mresim(*args: str | Path) -> list[str]:
    """The command line of ``mresim`` run from this interpreter."""
    return [sys.executable, "-m", "mresim_phys.cli", *map(str, args)]


def rows_on_disk(out: Path) -> bool:
    """Whether the run writing into ``out``'s temporary sibling has flushed metrics rows."""
    partial = out.parent.glob(f"{out.name}.tmp-*/.metrics.tmp-*.csv")
    return any(p.stat().st_size > 0 for p in partial if p.is_file())


def trial(
    folder: Path, sig: signal.Signals, bar: bool, double: bool, delay_s: float = 0.0
) -> Trial:
    """Run, interrupt and check one ``mresim run`` in ``folder`` (created if missing)."""
    folder.mkdir(parents=True, exist_ok=True)
    scenario, out = long_scenario(folder), folder / "run"
    flags = ["--out", out, "--no-plots", *([] if bar else ["--quiet"])]
    result = Trial(sig.name, bar, double)
    with (folder / "stderr.txt").open("w+") as err, (folder / "stdout.txt").open("w+") as std:
        process = subprocess.Popen(mresim("run", scenario, *flags), stdout=std, stderr=err)
        started = time.monotonic()
        while not rows_on_disk(out) and process.poll() is None:
            if time.monotonic() - started > STARTUP_TIMEOUT_S:
                break
            time.sleep(0.02)
        time.sleep(delay_s)
        process.send_signal(sig)
        if double:
            time.sleep(SECOND_SIGNAL_S)
            if process.poll() is None:
                process.send_signal(sig)
        try:
            code = process.wait(timeout=STARTUP_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            process.kill()
            code = process.wait()
        err.seek(0)
        result.lost = problems(out, code, sig, err.read())
    return result


def problems(out: Path, code: int, sig: signal.Signals, stderr: str) -> list[str]:
    """What the interrupted run in ``out`` lost or got wrong (empty: nothing)."""
    found = []
    if code != 128 + sig:
        found.append(f"exit status {code}, not {128 + sig}")
    if "Traceback" in stderr or "Error" in stderr:
        found.append("error on stderr: " + stderr.strip().splitlines()[-1])
    if not (out / "summary.json").is_file():
        return [*found, "no summary.json"]
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    if (summary["stop_reason"], summary.get("signal")) != ("interrupted", sig.name):
        found.append(f"summary says {summary['stop_reason']}, {summary.get('signal')}")
    rows = len((out / "metrics.csv").read_text(encoding="utf-8").splitlines()) - 1
    meta = json.loads((out / "log" / "meta.json").read_text(encoding="utf-8"))
    if not rows == meta["steps"] == summary["steps"] + 1 or not meta["closed"]:
        found.append(f"{rows} metrics rows, {meta['steps']} logged steps, {summary['steps']} + 1")
    if not (out / "final.png").is_file():
        found.append("no final.png")
    replay = subprocess.run(mresim("replay", out, "--metrics"), capture_output=True, text=True)
    if replay.returncode != 0 or "identical" not in replay.stdout:
        found.append(f"replay --metrics: {replay.stdout.strip()} {replay.stderr.strip()}")
    return found


def main(argv: list[str] | None = None) -> int:
    """Run the trials and print how many runs each combination lost."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--trials", type=int, default=20, help="trials per combination")
    parser.add_argument("--jobs", type=int, default=2, help="runs at once")
    args = parser.parse_args(argv)
    plan = [
        (sig, bar, n)
        for sig in (signal.SIGINT, signal.SIGTERM)
        for bar in (True, False)
        for n in range(args.trials)
    ]
    ctrl_c_reaches_children()
    delays = random.Random(0)
    started = time.monotonic()
    with tempfile.TemporaryDirectory() as tmp, ThreadPoolExecutor(args.jobs) as pool:
        futures = [
            pool.submit(
                trial, Path(tmp) / f"{s.name}-{b}-{n}", s, b, n % 2 == 1, delays.uniform(0, 0.4)
            )
            for s, b, n in plan
        ]
        results = [f.result() for f in futures]
    for sig in ("SIGINT", "SIGTERM"):
        for bar in (True, False):
            mine = [r for r in results if (r.signal, r.bar) == (sig, bar)]
            lost = [r for r in mine if r.lost]
            state = "on " if bar else "off"
            print(f"{sig:8} bar {state}: {len(mine) - len(lost)} ok, {len(lost)} lost")
            for r in lost:
                print(f"    {'double' if r.double else 'single'}: {'; '.join(r.lost)}")
    print(f"{len(results)} trials in {time.monotonic() - started:.0f} s")
    return 1 if any(r.lost for r in results) else 0


if __name__ == "__main__":
    sys.exit(main())
