"""The viewer's server survives random requests and messages, and refuses other sites.

``tools/fuzz_viewer.py`` holds the generators and the judge: a replay served on loopback
gets random HTTP requests (methods, paths, ``Host`` and ``Origin`` of its own, absent or
of another site, odd headers and bodies, bytes that are no HTTP) and random WebSocket
sessions (odd values, random and deeply nested JSON, big and binary messages). It must
never answer 5xx or log an error, must keep serving the page, and must refuse (403)
every request naming another site.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

ROOT = Path(__file__).resolve().parent.parent


def load_tool() -> ModuleType:
    """tools/fuzz_viewer.py as a module (it is a script, not part of the package)."""
    spec = importlib.util.spec_from_file_location("fuzz_viewer", ROOT / "tools/fuzz_viewer.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


fuzz = load_tool()
GENERATED = 300  # cases in the suite (about 20 s); tools/fuzz_viewer.py runs more


def test_random_requests_and_messages_never_break_the_viewer(tmp_path: Path) -> None:
    tally = fuzz.fuzz(GENERATED, tmp_path, seed=None)  # derandomized: reproducible
    counts = tally.counts
    assert not tally.failures, "\n\n".join(f"{case}\n{why}" for case, why in tally.failures)
    assert fuzz.cases_in(counts) >= GENERATED and counts["checks"] >= GENERATED // 25
    # the cases reach what they are meant to: refusals, served files, bad messages, limits
    assert counts["http 403"] >= 30 and counts["http 200"] + counts["http 404"] >= 20, counts
    assert counts["ws error replies"] >= 50 and counts["ws frames"] >= 50, counts
    assert counts["ws closed 1009"] + counts["ws closed 1006"] >= 1, counts
