"""Progress off a terminal (``output/progress.py``): each update once, a whole line, no
carriage returns piling up in a log; a first run without compiled kernels says so."""

from __future__ import annotations

import io
import os
import subprocess
import sys
from pathlib import Path

from mresim_phys.output.progress import LineWriter

ROOT = Path(__file__).resolve().parent.parent


def test_a_run_logged_to_a_file_prints_each_update_once(tmp_path: Path) -> None:
    scenario = str(ROOT / "scenarios" / "01_quickstart.yaml")
    command = [sys.executable, "-m", "mresim_phys.cli", "run", scenario, "--no-plots"]
    done = subprocess.run(
        [*command, "--out", str(tmp_path / "run")], capture_output=True, text=True, check=True
    )
    lines = [line for line in done.stderr.splitlines() if line.startswith("quickstart")]
    assert "\r" not in done.stderr
    assert len(lines) >= 2 and len(lines) == len(set(lines))
    assert "100%" in lines[-1]


def test_the_line_writer_drops_redraws_and_repeats() -> None:
    out = io.StringIO()
    writer = LineWriter(out)
    writer.write("\ra: 10%")
    writer.write("\ra: 10%")
    writer.write("\ra: 20%\n")
    assert out.getvalue() == "a: 10%\na: 20%\n"


def test_a_first_run_says_it_compiles(tmp_path: Path) -> None:
    """numba decides its cache folder when it loads (here NUMBA_CACHE_DIR): a fresh process."""
    probe = (
        "from mresim_phys.output.progress import first_run_note, kernel_cache, kernels_cached\n"
        "print(kernel_cache(), kernels_cached(), first_run_note() is not None)"
    )
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}

    def ask() -> list[str]:
        done = subprocess.run(
            [sys.executable, "-c", probe], env=env, capture_output=True, text=True, check=True
        )
        return done.stdout.split()

    folder, cached, note = ask()
    assert Path(folder).is_relative_to(tmp_path) and (cached, note) == ("False", "True")
    Path(folder).mkdir(parents=True, exist_ok=True)
    (Path(folder) / "raycast.cast_fan-1.py311.nbi").write_bytes(b"")
    assert ask()[1:] == ["True", "False"]
