"""Tests for tools/original_aisles.py: which aisles our robots enter, against pixel robots."""

from __future__ import annotations

from pathlib import Path
from types import ModuleType

import numpy as np
import pytest
from tool_modules import load_tool

aisles: ModuleType = load_tool("original_aisles")


def two_rooms(gap: int) -> np.ndarray:
    """Two 20x20 rooms in a wall mass, joined by a corridor ``gap`` pixels wide."""
    occupied = np.ones((30, 60), dtype=bool)
    occupied[5:25, 5:25] = False
    occupied[5:25, 35:55] = False
    occupied[14 : 14 + gap, 25:35] = False
    return occupied


def test_a_wide_corridor_lets_both_clearances_into_the_far_room() -> None:
    count, (planner, body) = aisles.shares(two_rooms(4), (10, 10))
    assert count == 2 * 400 + 4 * 10
    assert planner == pytest.approx(1.0)
    assert body == pytest.approx(1.0)


def test_a_two_pixel_aisle_is_entered_by_the_body_but_not_by_the_planner() -> None:
    count, (planner, body) = aisles.shares(two_rooms(2), (10, 10))
    assert count == 2 * 400 + 2 * 10
    assert planner < 0.6  # the far room is out of its reach
    assert body == pytest.approx(1.0)


def test_a_missing_original_tree_exits_2(tmp_path: Path) -> None:
    assert aisles.main(["--original", str(tmp_path)]) == 2


def test_a_diagonal_pinch_lets_pixel_robots_through_but_not_ours() -> None:
    occupied = two_rooms(1)
    occupied[14, 25:35] = True  # close the corridor, then open a zigzag of pixels that
    for k in range(10):  # touch only at their corners
        occupied[10 + k % 2, 25 + k] = False
    count, (_, body) = aisles.shares(occupied, (10, 10))
    assert count == 2 * 400 + 10  # 8-connected: the pixel robot goes through
    assert body < 0.6  # ours does not: the far room is out of its reach


def test_a_base_on_a_wall_or_off_the_map_is_an_error_not_a_count() -> None:
    occupied = two_rooms(4)
    for seed in ((0, 0), (500, 10)):  # the outer wall; below the map
        with pytest.raises(aisles.CompareError, match="base pixel"):
            aisles.shares(occupied, seed)
