"""The viewer's server survives random requests and messages, and refuses other sites.

``tools/fuzz_viewer.py`` holds the generators and the judge: a replay served on loopback
gets random HTTP requests (methods, paths, ``Host`` and ``Origin`` of its own, absent or
of another site, odd headers and bodies, bytes that are no HTTP) and random WebSocket
sessions (odd values, random and deeply nested JSON, big and binary messages). It must
never answer 5xx or log an error, must keep serving the page, and must refuse (403)
every request naming another site.
"""

from __future__ import annotations

from pathlib import Path

from tool_modules import load_tool

ROOT = Path(__file__).resolve().parent.parent


fuzz = load_tool("fuzz_viewer")
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
