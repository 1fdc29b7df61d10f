"""Shared fixtures: tiny maps and scenarios built in code, written into tmp_path."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from PIL import Image


def rooms_grid() -> np.ndarray:
    """A 60x80 map: outer wall, a vertical wall with a door, a room with a diagonal wall."""
    occ = np.zeros((60, 80), dtype=bool)
    occ[:2, :] = occ[-2:, :] = True
    occ[:, :2] = occ[:, -2:] = True
    occ[:, 40:42] = True
    occ[25:37, 40:42] = False  # a 12-cell door
    for i in range(12):  # a staircase diagonal wall in the right room
        occ[10 + i, 55 + i : 57 + i] = True
    return occ


def write_png(path: Path, occupied: np.ndarray) -> Path:
    """Save ``occupied`` as a black (obstacle) on white PNG."""
    Image.fromarray(np.where(occupied, 0, 255).astype(np.uint8)).save(path)
    return path


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(0)


@pytest.fixture
def rooms() -> np.ndarray:
    return rooms_grid()


def write_scenario(folder: Path, **changes: Any) -> Path:
    """Write a scenario over the rooms map into ``folder``; keyword arguments replace
    top-level keys."""
    write_png(folder / "rooms.png", rooms_grid())
    data: dict[str, Any] = {
        "name": "tiny",
        "seed": 3,
        "steps": 60,
        "map": {"image": "rooms.png", "resolution": 0.1},
        "base_station": {"position": [8, 30], "comm_range": 20},
        "team": {"speed": 2, "radius": 1.0, "sensor": {"range": 30}, "comm_range": 20},
        "robots": [
            {"name": "A", "start": [8, 20], "heading_deg": 0},
            {"name": "B", "start": [8, 40], "heading_deg": 0, "speed": 3},
        ],
    }
    data.update(changes)
    path = folder / "scenario.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


@pytest.fixture
def scenario_file(tmp_path: Path) -> Callable[..., Path]:
    """Write a scenario over the rooms map; keyword arguments replace top-level keys."""

    def make(**changes: Any) -> Path:
        return write_scenario(tmp_path, **changes)

    return make


QUICKSTART = Path(__file__).resolve().parent.parent / "scenarios" / "01_quickstart.yaml"


def write_study(folder: Path, **fields: Any) -> Path:
    """A study of the quickstart scenario (2 seeds, 8 steps a run unless ``fields`` say
    otherwise) written into ``folder`` as study.yaml."""
    data = {"name": "t", "scenarios": [str(QUICKSTART)], "seeds": 2, "steps": 8, **fields}
    path = folder / "study.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return path


def csv_row(record: Any) -> list[str]:
    """A step record's ``metrics.csv`` row with every column a run may have (None: '')."""
    from mresim_phys.columns import FLAGS, Layout

    return Layout(tuple(r.name for r in record.robots), frozenset(FLAGS)).row(record)


@pytest.fixture
def searched_from(monkeypatch: pytest.MonkeyPatch) -> list[tuple[float, float]]:
    """The start of every teammate path search the frontier auction runs (its calls of
    ``planning.goals.goal_costs``), in order; the searches themselves run as usual."""
    import mresim_phys.strategies.auction as auction

    starts: list[tuple[float, float]] = []
    real = auction.goal_costs

    def counted(passable: np.ndarray, start_xy: tuple[float, float], *args: Any) -> Any:
        starts.append(start_xy)
        return real(passable, start_xy, *args)

    monkeypatch.setattr(auction, "goal_costs", counted)
    return starts
