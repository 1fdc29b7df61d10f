"""Knowledge (phase 3): what each robot knows, never the truth.

``mapping`` (scans folded into a robot's own grid; the coverage counter), ``frontiers``
(frontier clusters and reachable targets) and ``teammates`` (records about teammates and
the strategy payloads they carry).
"""
