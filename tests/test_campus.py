"""Scale (issue 37): per-robot grids take memory where the robot knows the map, and the
campus benchmark draws its building once and keeps it."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from mresim_phys import memory
from mresim_phys.agents import empty_belief
from mresim_phys.cli import main
from mresim_phys.comms.deltas import select_cells
from mresim_phys.comms.ledger import NEVER, Ledger
from mresim_phys.output import campus
from mresim_phys.output.bench import PRESETS, run_bench
from mresim_phys.types import FREE

linux_only = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc/self/statm")
# a grid under glibc's raised mmap threshold (``memory.py``) may reuse freed heap memory,
# which calloc zeroes by writing: at most what the heap keeps freed
FREED = memory.TRIM_THRESHOLD / 2**20


def resident_mb() -> float:
    """This process's resident memory now, in MB."""
    pages = int(Path("/proc/self/statm").read_text().split()[1])
    return pages * 4096 / 2**20


@linux_only
def test_a_teams_grids_on_a_campus_take_memory_only_where_it_has_been() -> None:
    """32 robots' beliefs, safe space and comm ledgers on 4000 x 4000 cells are 4.2 GB of
    arrays; as long as the robots know nothing they cost next to nothing, and a robot that
    learns a 400 x 400 patch pays for that patch's rows, not for the map."""
    shape, n = (4000, 4000), 32
    before = resident_mb()
    grids = [empty_belief(shape) for _ in range(n)]
    ledger = Ledger(shape, n + 1)
    nominal = sum(b.nbytes + s.nbytes for b, s in grids) + sum(
        g.nbytes for g in (*ledger.stamps, *ledger.origins, *ledger.copies)
    )
    assert nominal > 4.1e9
    assert resident_mb() - before < FREED + 150
    belief, safe = grids[0]
    belief[1000:1400, 2000:2400] = FREE
    ledger.note(1, (1000, 1400, 2000, 2400))
    ledger.stamp_sensed(1, belief, safe, 0)
    assert int(np.count_nonzero(ledger.stamps[1])) == 400 * 400
    assert resident_mb() - before < FREED + 150 + 40  # 400 rows of 5 grids: ~2 pages each


def test_the_campus_map_is_drawn_once_then_taken_from_the_cache(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(campus, "CAMPUS_SIZE", 300)
    png = campus.campus_map(tmp_path)
    assert png.is_file() and png.parent.name == "campus-300-seed1"
    drawn = png.stat().st_mtime_ns
    assert campus.campus_map(tmp_path) == png
    assert png.stat().st_mtime_ns == drawn  # kept, not drawn again
    meta = png.parent / "map.yaml"
    meta.write_text(meta.read_text().replace("generator:", "generator: 0\nold:"))
    campus.campus_map(tmp_path)
    assert png.stat().st_mtime_ns != drawn  # another generator's drawing is replaced


def test_the_campus_preset_times_a_team_with_disk_links_on_the_drawn_building(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(campus, "CAMPUS_SIZE", 300)
    monkeypatch.setenv("MRESIM_CACHE", str(tmp_path))
    assert PRESETS["campus"].communication == {"model": "disk"}
    text = run_bench([4], None, 1, 2, "campus")
    assert "mresim bench --preset campus" in text
    assert (tmp_path / "campus-300-seed1" / "map.png").is_file()
    assert "peak resident memory of this process:" in text


@pytest.mark.parametrize(("agents", "dtype"), [(255, np.uint8), (256, np.int16)])
def test_a_cells_origin_takes_a_byte_while_every_agent_and_own_fit_in_it(
    agents: int, dtype: type
) -> None:
    """The last agent's own cells (origin OWN, a byte's 255) go to every receiver, and a
    cell that came from the receiver never goes back to it."""
    ledger = Ledger((8, 8), agents)
    last = agents - 1
    assert ledger.origins[last].dtype == dtype
    belief, safe = empty_belief((8, 8))
    belief[:2] = FREE
    ledger.note(last, (0, 2, 0, 8))
    ledger.stamp_sensed(last, belief, safe, 0)
    boxes = np.array([[0, 8, 0, 8]], np.int64)
    grids = (ledger.stamps[last], ledger.tiles[last], ledger.origins[last], ledger.copies[last])
    for receiver in (0, last - 1):
        index, _ = select_cells(boxes, NEVER, receiver, *grids, ledger.copies[receiver], False)
        assert len(index) == 16
    ledger.origins[last][0, :] = last - 1  # as if the first row came from agent last - 1
    index, _ = select_cells(boxes, NEVER, last - 1, *grids, ledger.copies[last - 1], False)
    assert sorted(index.tolist()) == list(range(8, 16))


def test_a_cache_folder_that_cannot_be_written_is_one_paragraph_and_exit_2(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    blocked = tmp_path / "file"
    blocked.write_text("not a folder")
    monkeypatch.setenv("MRESIM_CACHE", str(blocked))
    assert main(["bench", "--preset", "campus", "--robots", "1", "--steps", "1"]) == 2
    err = capsys.readouterr().err
    assert "MRESIM_CACHE" in err and str(blocked) in err and "Traceback" not in err
