"""A commit checked out beside this tree, for the benchmarks that compare against it.

``with checked_out(ROOT, "HEAD~3", "bench_against.py") as old:`` gives a temporary git
worktree of the commit (removed afterwards); a commit git cannot check out ends the
script with its message and exit status 2.
"""

from __future__ import annotations

import subprocess
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def checked_out(root: Path, rev: str, script: str) -> Iterator[Path]:
    """A temporary worktree of ``rev`` of the repository at ``root`` (``script`` names the
    caller in an error)."""
    with tempfile.TemporaryDirectory() as scratch:
        old = Path(scratch) / "before"
        added = subprocess.run(
            ["git", "-C", str(root), "worktree", "add", "--detach", str(old), rev],
            capture_output=True,
            text=True,
        )
        if added.returncode != 0:
            print(f"{script}: cannot check out {rev!r}: {added.stderr.strip()}")
            raise SystemExit(2)
        try:
            yield old
        finally:
            subprocess.run(["git", "-C", str(root), "worktree", "remove", "--force", str(old)])
