"""Views (phase 8), meeting marks: the rendezvous accounting's judgements on a frame.

With the global layer ``meetings`` on, a frame of a run whose strategies plan meetings
marks each meeting judged in the last ``MARK_STEPS`` steps (``meeting_board.py``) at
the points of the parties it bound: a kept one with a green ring, a missed one with a red
cross and the letter of its reason (``F`` partner failed, ``L`` late, ``N`` no link: the
link failed at the point). The legend shows both marks while the run has meetings.

Typical use: ``draw_meetings(image, snap.meetings, px, style)``.
"""

from __future__ import annotations

from collections.abc import Callable

import cv2
import numpy as np

from mresim_phys.meeting_board import LETTERS, MeetingBoard
from mresim_phys.render.style import AA, BGR, FONT, ONE, SHIFT, Style

KEPT, MISSED = "meeting kept", "meeting missed"  # legend marks
RING_PX = 7  # radius of a kept meeting's ring, pixels
ARM_PX = 5  # half-size of a missed meeting's cross, pixels


def draw_meetings(
    image: np.ndarray, board: MeetingBoard, px: Callable[[np.ndarray], np.ndarray], style: Style
) -> None:
    """The marks of the board's recent judgements (module docstring)."""
    for outcome in board.recent:
        points = [p for p in outcome.meeting.points if p is not None]
        if not points:
            continue
        for centre in px(np.array(points, dtype=float)):
            if outcome.result == "kept":
                cv2.circle(image, (int(centre[0]), int(centre[1])), RING_PX * ONE,
                           style.meeting_kept, 2, AA, SHIFT)  # fmt: skip
            else:
                letter = LETTERS.get(outcome.reason or "", "?")
                missed_mark(image, centre, letter, style.meeting_missed, style)


def missed_mark(
    image: np.ndarray, centre: np.ndarray, letter: str, colour: BGR, style: Style
) -> None:
    """A cross at the fixed-point ``centre`` and ``letter`` up and right of it."""
    for d in np.array(((1, 1), (1, -1)), dtype=np.int32) * ARM_PX * ONE:
        cv2.line(image, centre - d, centre + d, colour, 2, AA, SHIFT)
    x, y = (int(v) >> SHIFT for v in centre)
    org = (x + ARM_PX + 2, y - ARM_PX)
    cv2.putText(image, letter, org, FONT, style.font_scale, (255, 255, 255), 3, AA)
    cv2.putText(image, letter, org, FONT, style.font_scale, colour, 1, AA)


def meeting_marks(board: MeetingBoard | None, on: frozenset[str]) -> tuple[str, ...]:
    """The legend's meeting marks: both, in a run with meetings and the layer on."""
    return (KEPT, MISSED) if board is not None and "meetings" in on else ()


def legend_mark(
    band: np.ndarray, kind: str, corner: tuple[int, int], side: int, style: Style
) -> None:
    """A meeting mark (:data:`KEPT` or :data:`MISSED`) in the ``side``-pixel square at
    ``corner``."""
    x, y = corner
    centre = np.array(((2 * x + side) * ONE // 2, (2 * y + side) * ONE // 2), dtype=np.int32)
    if kind == KEPT:
        cv2.circle(band, (int(centre[0]), int(centre[1])), (side * ONE) // 2 - ONE // 2,
                   style.meeting_kept, 2, AA, SHIFT)  # fmt: skip
        return
    for d in np.array(((1, 1), (1, -1)), dtype=np.int32) * (side * ONE // 2 - ONE):
        cv2.line(band, centre - d, centre + d, style.meeting_missed, 2, AA, SHIFT)
