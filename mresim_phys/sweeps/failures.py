"""Random robot failures (sweeps, input): the ``failures`` axis, k robots fail per seed.

For a run with seed ``s`` and ``failures: k``, the stream ``sweep/failures`` of seed ``s``
(``rng.Streams``) orders the team at random and draws one failure step per robot,
uniformly between the study's ``failure_window`` fractions of the step cap; the first
``k`` robots of that order fail (a scheduled ``fail`` event each, added to the scenario's
events). The draws depend only on the seed, the team's names and the step cap, never on
the strategy: arms with the same seed and team meet the same failures (common random
numbers), and the robots failing with ``k`` also fail with ``k + 1``.
"""

from __future__ import annotations

import copy
from typing import Any

from mresim_phys.rng import Streams
from mresim_phys.sweeps.study import StudyError

STREAM = "sweep/failures"


def failure_plan(
    names: list[str], seed: int, steps: int, window: tuple[float, float]
) -> list[tuple[str, int]]:
    """Every robot of ``names`` in the seed's failure order, with its failure step.

    >>> failure_plan(["A", "B"], 3, 100, (0.1, 0.5)) == failure_plan(["A", "B"], 3, 100, (0.1, 0.5))
    True
    """
    rng = Streams(seed).get(STREAM)
    ordered = sorted(names)  # the order of the team in the file does not matter
    order = rng.permutation(len(ordered))
    first = max(1, int(window[0] * steps))
    last = max(first, int(window[1] * steps))
    times = rng.integers(first, last + 1, size=len(ordered))
    return [(ordered[i], int(t)) for i, t in zip(order, times, strict=True)]


def with_failures(
    data: dict[str, Any],
    names: list[str],
    k: int,
    seed: int,
    steps: int,
    window: tuple[float, float],
    source: str,
) -> dict[str, Any]:
    """``data`` with ``k`` robots failing at the seed's random steps (``fail`` events)."""
    if k > len(names):
        raise StudyError(
            f"{source}: axis failures: {k} failures asked for a team of {len(names)} robots"
            f" ({names}); sweep at most {len(names)}."
        )
    if k == 0:
        return data
    result = copy.deepcopy(data)
    plan = failure_plan(names, seed, steps, window)[:k]
    events = list(result.get("events") or [])
    events += [{"step": step, "fail": name} for name, step in sorted(plan, key=lambda p: p[1])]
    result["events"] = events
    return result
