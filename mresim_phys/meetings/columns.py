"""Rendezvous accounting (phase 7, metrics), the columns: ``meetings_planned``,
``meetings_kept``, ``meetings_missed`` (cumulative) and ``meetings_pending``, read from the
step's :class:`~mresim_phys.meeting_board.MeetingBoard` (``StepRecord.meetings``; empty in
a run whose strategies plan no meetings, which has no such columns).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from mresim_phys.columns import column
from mresim_phys.meeting_board import Tally

if TYPE_CHECKING:
    from mresim_phys.metrics import StepRecord


def _tally(r: StepRecord) -> Tally | None:
    return None if r.meetings is None else r.meetings.tally


@column("meetings_planned", optional=True)
def meetings_planned(r: StepRecord) -> int | None:
    """Meetings planned so far (their parties parted holding them)."""
    t = _tally(r)
    return None if t is None else t.planned


@column("meetings_kept", optional=True)
def meetings_kept(r: StepRecord) -> int | None:
    """Meetings kept so far (the parties linked on the main channel within the window)."""
    t = _tally(r)
    return None if t is None else t.kept


@column("meetings_missed", optional=True)
def meetings_missed(r: StepRecord) -> int | None:
    """Meetings missed so far, whatever the reason."""
    t = _tally(r)
    return None if t is None else t.missed_total


@column("meetings_pending", optional=True)
def meetings_pending(r: StepRecord) -> int | None:
    """Planned meetings not judged yet."""
    t = _tally(r)
    return None if t is None else t.pending()
