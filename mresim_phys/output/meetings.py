"""summary.json's ``meetings`` object (output): the rendezvous accounting of a run.

A run whose strategies plan meetings (``meetings/watch.py``) gets, besides its columns
(``meetings_planned``, ``meetings_kept``, ``meetings_missed``, ``meetings_pending``):

* ``planned``, ``kept``, ``missed`` (per reason and ``total``), ``superseded`` and the
  ``pending`` left at the end (planned = kept + missed + superseded + pending);
* ``keep_rate``: kept / (kept + missed) (null before any was judged);
* ``waiting``: the mean and median of the steps a party spent at its point, over the
  kept and missed meetings and the robots each bound (``parties``: how many);
* ``pairs``: the same counts per pair of parties (``"A-B"``, ``"base-C"``).

Rules: ``docs/rendezvous.md``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from mresim_phys.meeting_board import REASONS, Meeting, Outcome

if TYPE_CHECKING:
    from mresim_phys.sim import Simulation

MEETINGS = "meetings"


def meetings_summary(sim: Simulation) -> dict[str, Any]:
    """summary.json's ``meetings`` object ({} for a run whose strategies plan none)."""
    watch = sim.meetings
    if watch is None:
        return {}
    pending = [m.meeting() for m in watch.open.values() if m.planned is not None]
    return {MEETINGS: summarise_meetings(watch.outcomes, pending)}


def summarise_meetings(outcomes: Sequence[Outcome], pending: Sequence[Meeting]) -> dict[str, Any]:
    """The object (module docstring) of these judgements and meetings still pending."""
    out = counts(outcomes, pending)
    judged = out["kept"] + out["missed"]["total"]
    out["keep_rate"] = out["kept"] / judged if judged else None
    waits = [w for o in outcomes if o.result != "superseded" for w in o.waited if w is not None]
    out["waiting"] = {
        "mean": float(np.mean(waits)) if waits else None,
        "median": float(np.median(waits)) if waits else None,
        "parties": len(waits),
    }
    pairs = sorted({o.meeting.parties for o in outcomes} | {m.parties for m in pending})
    out["pairs"] = {
        "-".join(pair): counts(
            [o for o in outcomes if o.meeting.parties == pair],
            [m for m in pending if m.parties == pair],
        )
        for pair in pairs
    }
    return out


def counts(outcomes: Sequence[Outcome], pending: Sequence[Meeting]) -> dict[str, Any]:
    """Planned, kept, missed (per reason, total), superseded and pending."""
    results = [o.result for o in outcomes]
    missed = {r: sum(o.reason == r for o in outcomes if o.result == "missed") for r in REASONS}
    return {
        "planned": len(outcomes) + len(pending),
        "kept": results.count("kept"),
        "missed": {**missed, "total": results.count("missed")},
        "superseded": results.count("superseded"),
        "pending": len(pending),
    }
