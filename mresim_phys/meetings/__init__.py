"""Rendezvous accounting (phase 7, metrics): the meetings strategies agree, judged from the truth.

``board.py``: what a step shows of them (the tally, the meetings pending, the outcomes of
the last steps), its run-log codec and the ``meetings_*`` columns; ``watch.py``: the
judge (:class:`~mresim_phys.meetings.watch.MeetingWatch`). Rules: ``docs/rendezvous.md``.
"""
