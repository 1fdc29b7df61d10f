"""Output (output edge): everything a run leaves on disk, and what reads it back.

``session`` (the run loop) feeds the recorders of ``recorders`` (metrics.csv and
summary.json, the run log, video frames and PNGs); ``runlog`` writes and replays run logs,
every snapshot field stored as ``logformat`` says; ``video`` encodes frames; ``replay``,
``plots`` and ``bench`` are the ``mresim replay``, ``plot`` and ``bench`` commands.
"""
