"""``mresim warmup`` (output edge): compile the simulator's kernels once, after an install.

The hot loops are numba kernels compiled for the machine they run on and kept in numba's
on-disk cache (``cache=True``): beside the installed modules when that folder is writable
(a venv, an editable checkout), else numba's user-wide cache folder, or ``NUMBA_CACHE_DIR``.
A run whose kernels are not in the cache compiles them first: the quickstart's first run
after an install took ~50 s on 2 cores, the later ones ~4 s.

This command runs short scenarios that between them call every kernel the shipped
scenarios call (``mresim_phys/data/warmup/*.yaml``, on the package's own maps), each as
``mresim run`` in a fresh process, so that the kernels they compile land in the cache
exactly as a user's run will look them up. The ``core`` profile (sensing, mapping,
frontiers, planning, disk comm, the PNG of the last step) runs first and alone; the others
then share it from the cache and compile only their own kernels, ``--workers`` at a time.
It prints each profile's seconds and where the cache is.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

from mresim_phys.errors import MresimError
from mresim_phys.output.progress import kernel_cache
from mresim_phys.parallel import usable_cores

CORE = "core"


@dataclass(frozen=True)
class Warmed:
    """One profile's run: its name, wall seconds, and the run's exit status."""

    name: str
    seconds: float
    status: int
    stderr: str


def profile_folder() -> Path:
    """The folder of the warm-up scenarios (package data)."""
    return Path(str(resources.files("mresim_phys") / "data" / "warmup"))


def profiles() -> dict[str, Path]:
    """Every warm-up scenario by name (its file's stem), ``core`` first."""
    found = {path.stem: path for path in sorted(profile_folder().glob("*.yaml"))}
    return {CORE: found.pop(CORE), **found}


def chosen_profiles(names: list[str] | None) -> dict[str, Path]:
    """The profiles to run (all when ``names`` is None); an unknown name is a user error."""
    every = profiles()
    if names is None:
        return every
    unknown = [name for name in names if name not in every]
    if unknown:
        raise MresimError(
            f"mresim warmup --profiles: no warm-up profile named {', '.join(unknown)}."
            f" The profiles are: {', '.join(every)} (see `mresim warmup --list`)."
        )
    return {name: every[name] for name in every if name in names}


def run_profile(name: str, scenario: Path, out: Path) -> Warmed:
    """``mresim run`` of one profile in a fresh process (so it compiles into, and loads from,
    the cache exactly as a user's run does)."""
    command = [sys.executable, "-m", "mresim_phys.launch", "run", str(scenario)]
    command += ["--out", str(out / name), "--overwrite", "--quiet"]
    started = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True, check=False)
    return Warmed(name, time.perf_counter() - started, done.returncode, done.stderr)


def warm_up(names: list[str] | None, workers: int) -> list[Warmed]:
    """Run the chosen profiles: ``core`` (if chosen) alone, then the rest ``workers`` at a
    time (threads waiting on processes)."""
    chosen = chosen_profiles(names)
    results: list[Warmed] = []
    with tempfile.TemporaryDirectory(prefix="mresim-warmup-") as folder:
        out = Path(folder)
        if CORE in chosen:
            results.append(run_profile(CORE, chosen.pop(CORE), out))
        with ThreadPoolExecutor(max_workers=max(workers, 1)) as pool:
            jobs = [pool.submit(run_profile, name, path, out) for name, path in chosen.items()]
            results += [job.result() for job in jobs]
    return results


def cache_folder() -> str:
    """Where numba keeps this package's compiled kernels, said for a user."""
    module_cache = kernel_cache()  # one folder per module's package
    package = Path(__file__).resolve().parent.parent
    if module_cache.is_relative_to(package):
        return f"{package}/**/__pycache__ (beside the modules)"
    return str(module_cache.parent)


def report(results: list[Warmed], total: float) -> str:
    """The lines ``mresim warmup`` prints."""
    lines = [f"  {w.name:<12} {w.seconds:6.1f} s" for w in results if w.status == 0]
    lines.insert(0, f"mresim warmup: {len(lines)} profiles in {total:.1f} s")
    lines.append(f"compiled kernels are cached in {cache_folder()}")
    return "\n".join(lines)


def failures(results: list[Warmed]) -> str:
    """A paragraph on the profiles whose run failed (empty when none did)."""
    failed = [w for w in results if w.status != 0]
    if not failed:
        return ""
    said = "; ".join(f"{w.name} (exit {w.status}): {_last_line(w.stderr)}" for w in failed)
    return (
        f"mresim warmup: {len(failed)} warm-up run(s) failed, so their kernels will compile"
        f" at a user's first run instead: {said}"
    )


def _last_line(text: str) -> str:
    lines = [line for line in text.strip().splitlines() if line.strip()]
    return lines[-1] if lines else "no message"


def warmup_command(args: argparse.Namespace) -> int:
    """``mresim warmup``: compile the kernels into numba's cache (module docstring)."""
    if args.list:
        for name, path in profiles().items():
            print(f"{name:<12} {_first_comment(path)}")
        return 0
    started = time.perf_counter()
    results = warm_up(args.profiles, args.workers or usable_cores())
    print(report(results, time.perf_counter() - started))
    problem = failures(results)
    if problem:
        print(problem, file=sys.stderr)
        return 1
    return 0


def _first_comment(path: Path) -> str:
    first = path.read_text(encoding="utf-8").splitlines()[0]
    return first.lstrip("# ").strip()
