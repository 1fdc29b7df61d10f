"""Shards (sweeps, input and compare): one slice of a study per job of a cluster's job
array, written into the same sweep folder, compared as one sweep.

``mresim sweep STUDY --shard i/N`` (i from 0 to N-1; without ``--shard``, a SLURM array
task's ``SLURM_ARRAY_TASK_ID`` less ``SLURM_ARRAY_TASK_MIN``, over
``SLURM_ARRAY_TASK_COUNT``) runs the runs at positions k of the study's run list with
k % N == i, into ``OUT/shards/<i>-of-<N>/``: a sweep folder of its own (its lock, manifest
and tables), so shards running at once never write the same file, and a shard run again
resumes its own slice. The slices of one N are disjoint and together hold every run once.
``mresim compare OUT`` reads the union of the shards' tables (:func:`read_shards`) and names
the shards that are missing or unfinished.
"""

from __future__ import annotations

import os
import re
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TypeVar

from mresim_phys.errors import MresimError

SHARDS = "shards"
T = TypeVar("T")


def parse_shard(text: str) -> tuple[int, int]:
    """``i/N`` as (i, N), 0 <= i < N; ValueError saying what is wrong."""
    found = re.fullmatch(r"\s*(\d+)\s*/\s*(\d+)\s*", text)
    if found is None:
        raise ValueError(f"give the shard as i/N (e.g. 0/10), got {text!r}")
    index, count = int(found.group(1)), int(found.group(2))
    if count < 1 or not 0 <= index < count:
        raise ValueError(f"shard {text!r}: i must be 0 to N-1 and N at least 1")
    return index, count


def shard_from_env(environ: Mapping[str, str] | None = None) -> tuple[int, int] | None:
    """The shard of a SLURM array task (None outside one)."""
    env = os.environ if environ is None else environ
    task, count = env.get("SLURM_ARRAY_TASK_ID"), env.get("SLURM_ARRAY_TASK_COUNT")
    if task is None or count is None:
        return None
    try:
        index = int(task) - int(env.get("SLURM_ARRAY_TASK_MIN", "0"))
        return parse_shard(f"{index}/{int(count)}")
    except ValueError as exc:
        raise MresimError(
            f"SLURM_ARRAY_TASK_ID={task}, SLURM_ARRAY_TASK_COUNT={count}: {exc}; give --shard"
            " i/N yourself"
        ) from None


def slice_of(runs: Sequence[T], index: int, count: int) -> list[T]:
    """The runs of shard ``index`` of ``count``: positions k with k % count == index."""
    return [run for k, run in enumerate(runs) if k % count == index]


def shard_folder(out: Path, index: int, count: int) -> Path:
    """Where shard ``index`` of ``count`` writes."""
    return out / SHARDS / f"{index}-of-{count}"


def shard_folders(out: Path) -> list[Path]:
    """The shard folders of ``out`` of its one shard count (MresimError on a mix)."""
    root = out / SHARDS
    found = sorted(p for p in root.iterdir() if re.fullmatch(r"\d+-of-\d+", p.name))
    counts = {p.name.split("-of-")[1] for p in found}
    if len(counts) > 1:
        raise MresimError(
            f"{root} holds shards of different counts ({', '.join(sorted(counts))}): the"
            " slices overlap; keep one count's folders"
        )
    return found


def missing_shards(present: list[Path]) -> list[str]:
    """The shard names of the count in ``present`` that have no finished folder."""
    if not present:
        return []
    count = int(present[0].name.split("-of-")[1])
    names = {p.name for p in present}
    return [f"{i}-of-{count}" for i in range(count) if f"{i}-of-{count}" not in names]


def note_missing(out: Path, missing: list[str]) -> None:
    """Say which shards the comparison lacks."""
    if missing:
        print(
            f"mresim compare: {out}: shards {', '.join(missing)} have not finished; comparing"
            " the runs of the others",
            file=sys.stderr,
        )
