"""Phase 4b: the grid searches' binary heap pops the smaller f first, the deeper node on a tie.

A* and JPS break ties between equal f values toward the deeper node (larger g), which keeps
them from widening over equal-cost plateaus; the heap's order is written without branches
(``grid._before``), and these tests hold it to the rule written with them.
"""

from __future__ import annotations

import math

from hypothesis import example, given, settings
from hypothesis import strategies as st

from mresim_phys.planning.grid import TIE, _before, heap_add, heap_new, heap_pop

ANY_FLOAT = st.floats(allow_nan=True, allow_infinity=True)
NEAR = st.sampled_from([0.0, TIE / 2, TIE, 2 * TIE, -TIE / 2, -2 * TIE])


def rule(fa: float, ga: float, fb: float, gb: float) -> bool:
    """Entry a goes before entry b: its f is smaller by more than TIE, or within TIE of
    b's and its g is larger (the rule as A* states it)."""
    if fa < fb - TIE:
        return True
    if fa > fb + TIE:
        return False
    return ga > gb


@settings(max_examples=400, deadline=None)
@given(ANY_FLOAT, ANY_FLOAT, ANY_FLOAT, ANY_FLOAT)
@example(math.nan, 1.0, 0.0, 0.0)  # a NaN f compares as a tie: depth decides
@example(0.0, 1.0, math.nan, 0.0)
@example(math.inf, 1.0, math.inf, 0.0)
def test_the_heap_order_is_the_rule_for_every_float(
    fa: float, ga: float, fb: float, gb: float
) -> None:
    assert _before(fa, ga, fb, gb) == rule(fa, ga, fb, gb)


@settings(max_examples=200, deadline=None)
@given(st.floats(0.0, 1e6), NEAR, st.floats(0.0, 1e6), st.floats(0.0, 1e6))
def test_f_values_within_tie_of_each_other_are_ordered_by_depth(
    f: float, offset: float, ga: float, gb: float
) -> None:
    other = f + offset
    if abs(offset) <= TIE and other - f == offset:  # the sum kept the offset exactly
        assert _before(f, ga, other, gb) == (ga > gb)


@settings(max_examples=100, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 40), st.integers(0, 40)), min_size=1, max_size=80))
def test_the_heap_pops_the_smallest_f_first_and_of_equal_f_the_deepest(
    keys: list[tuple[int, int]],
) -> None:
    """f values a quarter apart (so ties are exact), pushed in any order: the pops come out
    sorted by (f, -g), the storage doubling as it fills."""
    entries = [(f / 4, g / 4) for f, g in keys]
    heap, size = heap_new(4), 0
    for node, (f, g) in enumerate(entries):
        heap, size = heap_add(heap, size, f, g, node)
    popped = []
    while size > 0:
        node, size = heap_pop(heap, size)
        popped.append(entries[node])
    assert sorted(popped, key=lambda e: (e[0], -e[1])) == popped
    assert sorted(popped) == sorted(entries)
