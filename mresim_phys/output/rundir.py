"""Run folders (output edge): a run writes a fresh folder and moves it into place at its end.

``mresim run`` never writes into an existing output folder. :class:`StagedRun` checks the
target first (:func:`check_target`): a missing or empty folder, or a run of the same
scenario (the ``name`` in its ``summary.json`` or ``scenario.yaml``), may be replaced; a run
of another scenario, a folder that is no run folder, or a file is refused unless
``overwrite``; the current folder (or one holding it) is always refused. The run then
writes into a temporary sibling (``<out>.tmp-<pid>-<hex>``), and :meth:`StagedRun.commit`
moves it onto the target (the old folder is renamed aside, the new one renamed in, the
old one deleted), so a reader never sees a mix of two runs, and a killed run leaves the
old folder as it was (and its temporary sibling beside it).
"""

from __future__ import annotations

import json
import os
import secrets
import shutil
from pathlib import Path

import yaml

from mresim_phys.errors import MresimError
from mresim_phys.output.files import WriteError, cause_of

RUN_FILES = ("summary.json", "scenario.yaml")  # what marks a folder as a run folder


def run_name(folder: Path) -> str | None:
    """The scenario name of the run in ``folder`` (summary.json, else scenario.yaml), or None
    when neither file exists or says."""
    for file in RUN_FILES:
        path = folder / file
        if not path.is_file():
            continue
        try:
            text = path.read_text(encoding="utf-8")
            data = json.loads(text) if path.suffix == ".json" else yaml.safe_load(text)
        except (OSError, UnicodeDecodeError, ValueError, yaml.YAMLError):
            continue
        name = data.get("name") if isinstance(data, dict) else None
        if isinstance(name, str):
            return name
    return None


def holds_cwd(folder: Path) -> bool:
    """Whether ``folder`` is the current folder or one of its parents."""
    here, target = Path.cwd().resolve(), folder.resolve()
    return here == target or target in here.parents


def refusal(out_dir: Path, what: str, name: str) -> MresimError:
    """The one-paragraph message refusing to replace ``out_dir``."""
    return MresimError(
        f"{out_dir} {what}, so `mresim run` will not replace it with a run of {name!r}."
        " Give another --out (a new or empty folder, or a run folder of the same scenario),"
        " or add --overwrite to replace the folder and everything in it."
    )


def check_target(out_dir: Path, name: str, overwrite: bool) -> None:
    """Refuse (MresimError) to replace ``out_dir`` unless it is free or a run of ``name``."""
    if (out_dir.exists() or out_dir.is_symlink()) and holds_cwd(out_dir):
        raise MresimError(
            f"{out_dir} is the current folder or holds it; a run replaces its output folder"
            " whole (even with --overwrite), so give it a folder of its own, e.g."
            f" runs/{name}/seed-N."
        )
    if overwrite or not (out_dir.exists() or out_dir.is_symlink()):
        return
    if not out_dir.is_dir():
        raise refusal(out_dir, "is a file, not a folder", name)
    held = run_name(out_dir)
    if held is None and any(out_dir.iterdir()):
        raise refusal(out_dir, "is not a run folder (no summary.json or scenario.yaml)", name)
    if held is not None and held != name:
        raise refusal(out_dir, f"holds a run of another scenario, {held!r}", name)


def fresh_sibling(out_dir: Path, tag: str) -> Path:
    """A new, not yet existing name beside ``out_dir``: ``<name>.<tag>-<pid>-<hex>``."""
    while True:
        path = out_dir.with_name(f"{out_dir.name}.{tag}-{os.getpid()}-{secrets.token_hex(3)}")
        if not (path.exists() or path.is_symlink()):
            return path


def remove(path: Path) -> None:
    """Delete a file, link or folder tree."""
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path)
    else:
        path.unlink(missing_ok=True)


class StagedRun:
    """A run folder written at ``folder`` (a temporary sibling) and moved onto ``target``."""

    def __init__(self, target: Path, name: str, overwrite: bool = False) -> None:
        """Check ``target`` (MresimError if refused) and create the temporary folder
        (WriteError naming ``target`` if that fails)."""
        self.target = Path(target)
        check_target(self.target, name, overwrite)
        self.folder = fresh_sibling(self.target, "tmp")
        try:
            self.folder.mkdir(parents=True)
        except OSError as exc:
            raise WriteError(self.target, f"cannot create its folder ({cause_of(exc)})") from exc

    def commit(self) -> Path:
        """Move the written folder onto the target, replacing what was there; the target."""
        aside = None
        if self.target.exists() or self.target.is_symlink():
            aside = fresh_sibling(self.target, "old")
            os.rename(self.target, aside)
        os.rename(self.folder, self.target)
        if aside is not None:
            remove(aside)
        return self.target

    def discard(self) -> None:
        """Delete the temporary folder (a run that failed leaves the target as it was)."""
        if self.folder.exists():
            shutil.rmtree(self.folder, ignore_errors=True)
