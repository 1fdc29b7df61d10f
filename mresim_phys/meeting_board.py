"""Rendezvous accounting (phase 7, metrics), the board: what one step shows of the meetings.

A :class:`MeetingBoard` is the accounting's state at the end of a step as everything
downstream sees it: the :class:`Tally` so far (planned, kept, missed by reason,
superseded), the meetings planned and not judged yet (:class:`Meeting`) and the
:class:`Outcome` s judged in the last :data:`MARK_STEPS` steps (kept and missed ones: the
marks frames draw). ``StepRecord.meetings`` and ``Snapshot.meetings`` hold it (None in a
run whose strategies plan no meetings); the run log stores it whole in each step's line
(:func:`encode` / :func:`decode`, full-precision floats), so a replay has the same
columns, marks and hover rows. The columns ``meetings_planned``, ``meetings_kept``,
``meetings_missed`` (cumulative) and ``meetings_pending`` read it
(``meetings/columns.py``). Rules: ``docs/rendezvous.md``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

REASONS = ("partner_failed", "late", "link_failed")  # a miss's reasons (the tally's order)
LETTERS = {"partner_failed": "F", "late": "L", "link_failed": "N"}  # on frames: F, L, N(o link)
MARK_STEPS = 15  # steps a judged meeting's mark stays on frames
Point = tuple[float, float]


@dataclass(frozen=True)
class Meeting:
    """A planned meeting: its two ``parties`` (agent order: the base first, then the
    robots in scenario order), each one's ``points`` (its own, believed frame; None: a
    party the meeting does not bind, as the base), the agreed ``step``, the last step of
    its window (``closes``) and the step it was ``planned`` (the parties parted holding it)."""

    parties: tuple[str, str]
    points: tuple[Point | None, Point | None]
    step: int
    closes: int
    planned: int


@dataclass(frozen=True)
class Outcome:
    """A judged meeting: ``result`` kept, missed (with ``reason``, one of :data:`REASONS`)
    or superseded, at step ``judged``; ``waited``: the steps each party spent at its
    point before (None: a party it does not bind)."""

    meeting: Meeting
    judged: int
    result: str
    reason: str | None = None
    waited: tuple[int | None, int | None] = (None, None)


@dataclass(frozen=True)
class Tally:
    """Meetings so far: planned, kept, missed per reason (:data:`REASONS` order), superseded."""

    planned: int = 0
    kept: int = 0
    missed: tuple[int, int, int] = (0, 0, 0)
    superseded: int = 0

    @property
    def missed_total(self) -> int:
        """Meetings missed, whatever the reason."""
        return sum(self.missed)

    def pending(self) -> int:
        """Planned meetings not judged yet."""
        return self.planned - self.kept - self.missed_total - self.superseded


@dataclass(frozen=True)
class MeetingBoard:
    """The accounting at the end of a step (module docstring)."""

    tally: Tally = field(default_factory=Tally)
    pending: tuple[Meeting, ...] = ()
    recent: tuple[Outcome, ...] = ()  # kept and missed, judged in the last MARK_STEPS steps


def _point(p: Point | None) -> list[float] | None:
    return None if p is None else [float(p[0]), float(p[1])]


def _meeting_json(m: Meeting) -> list[Any]:
    return [list(m.parties), [_point(p) for p in m.points], m.step, m.closes, m.planned]


def _meeting(raw: list[Any]) -> Meeting:
    parties, points, step, closes, planned = raw
    a, b = ((None if p is None else (float(p[0]), float(p[1]))) for p in points)
    return Meeting((str(parties[0]), str(parties[1])), (a, b), int(step), int(closes), int(planned))


def encode(board: MeetingBoard) -> dict[str, Any]:
    """The run log's ``meetings`` object of a step."""
    t = board.tally
    return {
        "tally": [t.planned, t.kept, *t.missed, t.superseded],
        "pending": [_meeting_json(m) for m in board.pending],
        "recent": [
            [_meeting_json(o.meeting), o.judged, o.result, o.reason, list(o.waited)]
            for o in board.recent
        ],
    }


def decode(raw: dict[str, Any], n: int = 0) -> MeetingBoard:
    """:func:`encode` read back (``n``, the agents, is not needed)."""
    planned, kept, f, late, link, superseded = (int(v) for v in raw["tally"])
    recent = tuple(
        Outcome(_meeting(m), int(judged), str(result), reason, (waited[0], waited[1]))
        for m, judged, result, reason, waited in raw["recent"]
    )
    pending = tuple(_meeting(m) for m in raw["pending"])
    return MeetingBoard(Tally(planned, kept, (f, late, link), superseded), pending, recent)


def pending_of(board: MeetingBoard | None, name: str) -> list[dict[str, Any]]:
    """The meetings pending for agent ``name`` as the viewer's hover row shows them."""
    if board is None:
        return []
    out = []
    for m in board.pending:
        if name in m.parties:
            mine = m.parties.index(name)
            point = m.points[mine]
            out.append({
                "with": m.parties[1 - mine],
                "at": None if point is None else [round(point[0], 1), round(point[1], 1)],
                "step": m.step,
                "closes": m.closes,
            })  # fmt: skip
    return out
