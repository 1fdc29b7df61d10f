"""Output (output edge): everything a run leaves on disk, and what reads it back.

``session`` (the run loop) feeds the recorders of ``recorders`` (metrics.csv and
summary.json, the run log, video frames and PNGs) into a fresh folder that ``rundir``
moves into place, stopping cleanly on the signals ``signals`` routes to it; ``files``
writes every file under a temporary name first (a failed write is a WriteError);
``logwriter`` writes run logs and ``runlog`` replays them, every snapshot field stored as
``logformat`` says (``logmeta`` checks their meta.json); ``video`` encodes frames;
``replay``, ``plots`` (reading runs through ``rundata``) and ``bench`` are the ``mresim
replay``, ``plot`` and ``bench`` commands.
"""
