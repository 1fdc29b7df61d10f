"""In-flight runs (sweeps, running): which process writes which run folder right now.

While a run runs, its worker keeps ``<sweep>/inflight/<run_id>.json`` (its
``lifeline.Owner``: pid, host, start) and touches it every :data:`HEARTBEAT` seconds; the
marker goes when the run ends, whatever the end. A worker killed mid-run leaves its marker
and a temporary run folder; a resume deletes both only once the marker's writer is dead
(on this host: its pid is gone; on another host: no heartbeat for :data:`STALE_AFTER`
seconds), and waits for runs whose writer still lives (an orphaned worker of a killed
sweep), so it never deletes a folder a live process writes, nor runs a run twice at once.
"""

from __future__ import annotations

import contextlib
import json
import os
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

from mresim_phys.output.files import write_json_atomic
from mresim_phys.sweeps.lifeline import Owner

INFLIGHT = "inflight"
HEARTBEAT = 5.0  # seconds between touches of a marker
STALE_AFTER = 60.0  # a marker of another host untouched this long is a dead writer's
POLL = 0.5  # seconds between checks while waiting for live writers


def marker(sweep: Path, run_id: str) -> Path:
    """The marker of run ``run_id``."""
    return Path(sweep) / INFLIGHT / f"{run_id}.json"


@contextlib.contextmanager
def in_flight(sweep: Path, run_id: str) -> Iterator[None]:
    """Hold the marker of ``run_id`` (with its heartbeat) while the block runs."""
    path = marker(sweep, run_id)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_json_atomic(path, Owner.me().to_json())
    stop = threading.Event()
    thread = threading.Thread(target=beat, args=(path, stop), name="mresim-heartbeat", daemon=True)
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join()
        with contextlib.suppress(OSError):
            path.unlink()


def beat(path: Path, stop: threading.Event) -> None:
    """Touch ``path`` every HEARTBEAT seconds until ``stop``."""
    while not stop.wait(HEARTBEAT):
        with contextlib.suppress(OSError):
            os.utime(path)


def writers(sweep: Path) -> dict[str, Owner]:
    """The runs a live process writes, by run id (markers of dead writers are deleted)."""
    folder = Path(sweep) / INFLIGHT
    live: dict[str, Owner] = {}
    if not folder.is_dir():
        return live
    for path in folder.glob("*.json"):
        try:
            owner = Owner.from_json(json.loads(path.read_text(encoding="utf-8")))
            beat_at = path.stat().st_mtime
        except (OSError, ValueError):
            owner, beat_at = None, 0.0
        if owner is not None and owner.alive(beat_at, STALE_AFTER):
            live[path.stem] = owner
        else:
            with contextlib.suppress(OSError):
                path.unlink()
    return live


def wait_for_writers(sweep: Path, notify: Callable[[str], None]) -> int:
    """Block until no live process writes a run of ``sweep`` (saying so once); how many
    runs there were to wait for."""
    waited: set[str] = set()
    while live := writers(sweep):
        if not waited:
            owners = sorted({o.describe() for o in live.values()})
            notify(
                f"waiting for {len(live)} run(s) of {sweep} that processes of an earlier sweep"
                f" still write ({'; '.join(owners[:3])}{' ...' if len(owners) > 3 else ''});"
                " they are kept when they finish. Stop those processes to go on at once."
            )
        waited |= set(live)
        time.sleep(POLL)
    return len(waited)
