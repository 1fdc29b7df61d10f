"""Sweep folders (sweeps, output edge): what a sweep has done, so a re-run does the rest.

A sweep folder holds ``sweep.json`` (the study's name, axes and reference, and a hash of
each run's scenario data by run id),
``study.yaml`` (the study as given), ``sweep.lock`` (``sweeps/lock.py``),
``manifest.jsonl`` (one line per finished attempt of a run: done, failed (the run's own
error) or lost (the machine's: a dead worker, a full disk, a lost Dask connection), with
its attempt number, appended and flushed to disk as each run ends; the last line of a run
counts), ``runs/<run_id>/`` (normal run folders, each renamed into place when complete),
``inflight/<run_id>.json`` (``sweeps/inflight.py``), ``errors/<run_id>.log`` and at the
end ``runs.parquet`` and ``steps.parquet``.

Re-running the same command after a kill runs only what is missing, and the lost runs
(``retry_failed``: the failed ones too): a run counts as done when the manifest says so
AND its folder is in place; a folder in place that the manifest missed (killed between the
rename and the line) is noted as done without running again; once no live process writes
a run of the folder (``inflight.wait_for_writers``), half-written temporary folders of
killed runs are deleted. Manifest lines that are not records of this sweep's runs are
skipped (the file is untrusted input). The same study with more runs
(more seeds, values added at the end of the first axis, base scenarios added at the end)
carries on in its folder; a folder
holding another study, or a run id whose scenario data changed, is refused.
"""

from __future__ import annotations

import contextlib
import json
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

from mresim_phys.output.files import WriteError, cause_of, write_json_atomic, write_text_atomic
from mresim_phys.output.rundir import remove
from mresim_phys.sweeps.expand import RunSpec
from mresim_phys.sweeps.inflight import wait_for_writers, writers
from mresim_phys.sweeps.lock import LOCK_FILE
from mresim_phys.sweeps.study import StudyError
from mresim_phys.sweeps.worker import DONE, FAILED, LOST, RUNS, STATUSES, run_folder

SWEEP_FILE = "sweep.json"
MANIFEST = "manifest.jsonl"
STUDY_COPY = "study.yaml"


class Manifest:
    """The finished runs of one sweep folder, and the file that records them."""

    def __init__(self, folder: Path, records: dict[str, dict[str, Any]]) -> None:
        self.folder = folder
        self.records = records

    def todo(self, runs: list[RunSpec], retry_failed: bool = False) -> list[RunSpec]:
        """The runs to run, in order: not finished yet, lost (and failed if
        ``retry_failed``)."""
        again = (LOST, FAILED) if retry_failed else (LOST,)
        return [
            r
            for r in runs
            if r.run_id not in self.records or self.records[r.run_id]["status"] in again
        ]

    def add(self, record: dict[str, Any]) -> None:
        """Note a finished attempt of a run (its attempt number counted here): one line,
        flushed to disk before returning."""
        if "attempt" not in record:
            before = self.records.get(record["run_id"])
            record = {**record, "attempt": attempt(before) + 1 if before else 1}
        self.records[record["run_id"]] = record
        path = self.folder / MANIFEST
        try:
            with path.open("ab", buffering=0) as file:  # unbuffered: one write, or none
                end = file.seek(0, os.SEEK_END)
                try:
                    file.write((json.dumps(record) + "\n").encode("utf-8"))
                    os.fsync(file.fileno())
                except OSError:
                    with contextlib.suppress(OSError):  # no half line for the next to join
                        file.truncate(end)
                    raise
        except OSError as exc:
            raise WriteError(path, cause_of(exc)) from exc

    def failed(self) -> list[dict[str, Any]]:
        """The records of failed runs."""
        return [r for r in self.records.values() if r["status"] == FAILED]

    def lost(self) -> list[dict[str, Any]]:
        """The records of lost runs."""
        return [r for r in self.records.values() if r["status"] == LOST]


def attempt(record: dict[str, Any]) -> int:
    """A record's attempt number (1 for records that do not say)."""
    value = record.get("attempt")
    return value if isinstance(value, int) and value >= 1 else 1


def open_sweep(
    folder: Path,
    info: dict[str, Any],
    runs: list[RunSpec],
    study_text: str,
    notify: Callable[[str], None] = print,
) -> Manifest:
    """The sweep folder ``folder`` for the study ``info["study"]`` (with its ``axes``,
    ``reference`` and the hashes of its ``runs``), created or resumed (its lock held by the
    caller); StudyError if it holds something else. Waits for runs a live process of an
    earlier sweep still writes (``notify`` says so)."""
    folder = Path(folder)
    check_folder(folder, info["study"], info["runs"])
    folder.mkdir(parents=True, exist_ok=True)
    old = read_info(folder / SWEEP_FILE) if (folder / SWEEP_FILE).is_file() else {}
    write_json_atomic(  # first: a folder with anything else is a sweep's
        folder / SWEEP_FILE, {**info, "runs": {**old.get("runs", {}), **info["runs"]}}
    )
    write_text_atomic(folder / STUDY_COPY, study_text)
    (folder / RUNS).mkdir(exist_ok=True)
    wait_for_writers(folder, notify)
    clean_leftovers(folder)
    records = read_records(folder / MANIFEST)
    manifest = Manifest(folder, {})
    for run_id, record in reconcile(folder, records, runs).items():
        if records.get(run_id) == record:
            manifest.records[run_id] = record
            continue
        manifest.add(record)  # a run found complete that the manifest missed
    return manifest


def check_folder(folder: Path, name: str, hashes: dict[str, str]) -> None:
    """Refuse a folder that is not free, nor a sweep of the same study whose runs (by id)
    hold the same scenario data."""
    if not folder.exists():
        return
    if not folder.is_dir():
        raise StudyError(f"{folder} is a file; give --out a folder for the sweep.")
    info_path = folder / SWEEP_FILE
    if not info_path.is_file():
        if any(not ours(p.name) for p in folder.iterdir()):
            raise StudyError(
                f"{folder} is not empty and holds no sweep ({SWEEP_FILE} is missing), so the"
                f" sweep of {name!r} will not write there. Give another --out."
            )
        return
    info = read_info(info_path)
    held, old = info.get("study"), info.get("runs")
    if held != name or not isinstance(old, dict):
        raise StudyError(
            f"{folder} holds a sweep of another study ({held!r}; this one is {name!r}). A"
            " sweep resumes only into its own folder: give another --out, or delete that"
            " folder to start over."
        )
    changed = sorted(r for r, h in hashes.items() if r in old and old[r] != h)
    if changed:
        raise StudyError(
            f"{folder} holds a sweep of {name!r} whose runs {changed[:3]}"
            f"{' and more' if len(changed) > 3 else ''} had other scenario data (a changed axis"
            " value, base scenario, override or step cap; run ids are a<arm>-s<seed>, so"
            " inserting an axis value renumbers the arms). Give another --out, or delete that"
            " folder to start over; more seeds, values added at the end of the first axis or"
            " scenarios added at the end carry on in the same folder."
        )


def ours(name: str) -> bool:
    """Whether a file of a folder without sweep.json is a sweep's first (the lock, or the
    temporary file of sweep.json of a sweep killed as it began)."""
    return name == LOCK_FILE or name.startswith(f".{Path(SWEEP_FILE).stem}.tmp-")


def read_info(path: Path) -> dict[str, Any]:
    """``sweep.json``; StudyError if it is damaged."""
    try:
        info = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise StudyError(f"{path}: cannot read the sweep record ({exc}).") from None
    if not isinstance(info, dict):
        raise StudyError(f"{path}: the sweep record is not a JSON object.")
    return info


def read_records(path: Path) -> dict[str, dict[str, Any]]:
    """The manifest's records by run id, the last line of a run counting (a line torn by a
    kill, or one that is no record, is skipped)."""
    records: dict[str, dict[str, Any]] = {}
    if not path.is_file():
        return records
    for line in path.read_text(encoding="utf-8", errors="replace").splitlines():
        try:
            record = json.loads(line)
        except ValueError:
            continue
        if valid_record(record):
            records[record["run_id"]] = record
    return records


def valid_record(record: Any) -> bool:
    """Whether a manifest line is a record of a run."""
    return (
        isinstance(record, dict)
        and isinstance(record.get("run_id"), str)
        and record.get("status") in STATUSES
    )


def reconcile(
    folder: Path, records: dict[str, dict[str, Any]], runs: list[RunSpec]
) -> dict[str, dict[str, Any]]:
    """Records of the runs that are really finished (done runs need their folder; a complete
    folder the manifest missed, or a lost run's, is a done run)."""
    known = {r.run_id for r in runs}
    kept = {k: r for k, r in records.items() if k in known and holds(folder, r)}
    for run in runs:
        if run.run_id not in kept and complete(run_folder(folder, run.run_id)):
            kept[run.run_id] = {
                "run_id": run.run_id,
                "status": DONE,
                "run_time_s": None,
                "error": None,
                "log": None,
                "attempt": attempt(records[run.run_id]) if run.run_id in records else 1,
            }
    return kept


def holds(folder: Path, record: dict[str, Any]) -> bool:
    """Whether a record is true of the folder: a done run's folder is in place, a lost
    run's is not (a worker that died after moving its folder into place did finish)."""
    if record["status"] == FAILED:
        return True
    done: bool = record["status"] == DONE
    return complete(run_folder(folder, record["run_id"])) == done


def complete(run_dir: Path) -> bool:
    """Whether a run folder is in place (folders appear whole, by a rename)."""
    return (run_dir / "summary.json").is_file()


def clean_leftovers(folder: Path) -> None:
    """Delete the temporary folders of runs killed mid-way (not those a live process
    still writes)."""
    busy = writers(folder)
    for path in (folder / RUNS).iterdir():
        name, tmp, _ = path.name.partition(".tmp-")
        if not tmp:
            name, tmp, _ = path.name.partition(".old-")
        if tmp and name not in busy:
            remove(path)
