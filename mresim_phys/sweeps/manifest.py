"""Sweep folders (sweeps, output edge): what a sweep has done, so a re-run does the rest.

A sweep folder holds ``sweep.json`` (the study's name, axes and reference, and a hash of
each run's scenario data by run id),
``study.yaml`` (the study as given), ``manifest.jsonl`` (one line per finished run: done
or failed, appended and flushed to disk as each run ends), ``runs/<run_id>/`` (normal run
folders, each renamed into place when complete), ``errors/<run_id>.log`` and at the end
``runs.parquet`` and ``steps.parquet``.

Re-running the same command after a kill runs only what is missing: a run counts as done
when the manifest says so AND its folder is in place; a folder in place that the manifest
missed (killed between the rename and the line) is noted as done without running again;
half-written temporary folders of killed runs are deleted. The same study with more runs
(more seeds, values added at the end of the first axis, base scenarios added at the end)
carries on in its folder; a folder
holding another study, or a run id whose scenario data changed, is refused.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

from mresim_phys.output.files import write_json_atomic, write_text_atomic
from mresim_phys.output.rundir import remove
from mresim_phys.sweeps.expand import RunSpec
from mresim_phys.sweeps.study import StudyError
from mresim_phys.sweeps.worker import DONE, FAILED, RUNS, run_folder

SWEEP_FILE = "sweep.json"
MANIFEST = "manifest.jsonl"
STUDY_COPY = "study.yaml"


class Manifest:
    """The finished runs of one sweep folder, and the file that records them."""

    def __init__(self, folder: Path, records: dict[str, dict[str, Any]]) -> None:
        self.folder = folder
        self.records = records

    def todo(self, runs: list[RunSpec]) -> list[RunSpec]:
        """The runs not finished yet, in order."""
        return [r for r in runs if r.run_id not in self.records]

    def add(self, record: dict[str, Any]) -> None:
        """Note a finished run: one line, flushed to disk before returning."""
        self.records[record["run_id"]] = record
        with (self.folder / MANIFEST).open("a", encoding="utf-8") as file:
            file.write(json.dumps(record) + "\n")
            file.flush()
            os.fsync(file.fileno())

    def failed(self) -> list[dict[str, Any]]:
        """The records of failed runs."""
        return [r for r in self.records.values() if r["status"] == FAILED]


def open_sweep(
    folder: Path, info: dict[str, Any], runs: list[RunSpec], study_text: str
) -> Manifest:
    """The sweep folder ``folder`` for the study ``info["study"]`` (with its ``axes``,
    ``reference`` and the hashes of its ``runs``), created or resumed; StudyError if it
    holds something else."""
    folder = Path(folder)
    check_folder(folder, info["study"], info["runs"])
    folder.mkdir(parents=True, exist_ok=True)
    (folder / RUNS).mkdir(exist_ok=True)
    old = read_info(folder / SWEEP_FILE) if (folder / SWEEP_FILE).is_file() else {}
    write_text_atomic(folder / STUDY_COPY, study_text)
    write_json_atomic(
        folder / SWEEP_FILE, {**info, "runs": {**old.get("runs", {}), **info["runs"]}}
    )
    clean_leftovers(folder / RUNS)
    records = read_records(folder / MANIFEST)
    manifest = Manifest(folder, {})
    for record in reconcile(folder, records, runs).values():
        if records.get(record["run_id"]) == record:
            manifest.records[record["run_id"]] = record
        else:
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
        if any(folder.iterdir()):
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
    """The manifest's records by run id (a line torn by a kill is skipped)."""
    records: dict[str, dict[str, Any]] = {}
    if not path.is_file():
        return records
    for line in path.read_text(encoding="utf-8").splitlines():
        try:
            record = json.loads(line)
        except ValueError:
            continue
        if isinstance(record, dict) and isinstance(record.get("run_id"), str):
            records[record["run_id"]] = record
    return records


def reconcile(
    folder: Path, records: dict[str, dict[str, Any]], runs: list[RunSpec]
) -> dict[str, dict[str, Any]]:
    """Records of the runs that are really finished (done runs need their folder; a complete
    folder the manifest missed is a done run)."""
    known = {r.run_id for r in runs}
    kept = {
        k: r
        for k, r in records.items()
        if k in known and (r["status"] != DONE or complete(run_folder(folder, k)))
    }
    for run in runs:
        if run.run_id not in kept and complete(run_folder(folder, run.run_id)):
            kept[run.run_id] = {
                "run_id": run.run_id,
                "status": DONE,
                "run_time_s": None,
                "error": None,
                "log": None,
            }
    return kept


def complete(run_dir: Path) -> bool:
    """Whether a run folder is in place (folders appear whole, by a rename)."""
    return (run_dir / "summary.json").is_file()


def clean_leftovers(runs_dir: Path) -> None:
    """Delete the temporary folders of runs killed mid-way."""
    for path in runs_dir.iterdir():
        if ".tmp-" in path.name or ".old-" in path.name:
            remove(path)
