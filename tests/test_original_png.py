"""Tests for tools/original_png.py: a corpus map written as the original MRESim reads one."""

from __future__ import annotations

from pathlib import Path
from types import ModuleType

import numpy as np
import pytest
from PIL import Image
from tool_modules import load_tool

original_png: ModuleType = load_tool("original_png")
corpus: ModuleType = load_tool("corpus")


def test_trim_drops_the_outer_rows_with_fewest_free_cells_first() -> None:
    free = np.zeros((6, 4), dtype=bool)
    free[0, 0] = True  # top row: 1 free cell
    free[1:5] = True
    free[5, :3] = True  # bottom row: 3 free cells
    cut, top, left = original_png.trim(free, height=4, width=4)
    assert cut.shape == (4, 4)
    assert (top, left) == (1, 0)  # the top row went first, then the bottom one
    assert cut.all()


def test_trim_keeps_a_map_that_fits() -> None:
    free = np.ones((3, 5), dtype=bool)
    cut, top, left = original_png.trim(free)
    assert cut.shape == (3, 5) and (top, left) == (0, 0)


def test_the_willow_map_is_exported_with_its_team(tmp_path: Path) -> None:
    (entry,) = corpus.select(corpus.load_index(), "willow_garage")
    png, team, lost = original_png.export(entry, tmp_path, tmp_path)
    image = np.asarray(Image.open(png))
    assert image.shape == (600, 800, 3)
    free = image[:, :, 0] > 0  # the original's rule: the first band is not 0
    assert int(free.sum()) == int(original_png.free_cells(entry).sum()) - lost
    assert 0 <= lost < 100  # a few tips of laser fans
    lines = team.read_text(encoding="utf-8").splitlines()
    assert len(lines) == 1 + len(entry.starts)
    assert lines[0].split()[1] == "BaseStation"
    for line in lines:
        x, y = (int(v) for v in line.split()[2:4])
        assert free[y, x], line  # every robot starts on a free pixel


def test_an_unknown_map_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert original_png.main(["nowhere", "--original", str(tmp_path)]) == 2
    assert "unknown corpus maps ['nowhere']" in capsys.readouterr().err


def test_an_unwritable_tree_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    blocker = tmp_path / "tree"
    blocker.write_text("a file, not a folder", encoding="utf-8")
    teams = tmp_path / "teams"
    teams.mkdir()
    code = original_png.main(["willow_garage", "--original", str(blocker), "--teams", str(teams)])
    assert code == 2
    assert "original_png:" in capsys.readouterr().err
