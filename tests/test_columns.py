"""Metric columns: the default set, optional and plugin columns, written live and replayed."""

from __future__ import annotations

import csv
import re
import sys
from pathlib import Path
from typing import Any

import pytest
from conftest import write_scenario

from mresim_phys import Simulation
from mresim_phys.cli import main
from mresim_phys.columns import COLUMNS, DEFAULTS, Layout, column, value_of
from mresim_phys.metrics import StepRecord

ROOT = Path(__file__).parent.parent
GUIDE = ROOT / "docs" / "metric-columns.md"


def docs_example(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The guide's column module saved as ``my_columns`` on the path."""
    block = re.findall(r"```python\n(.*?)```", GUIDE.read_text(encoding="utf-8"), re.S)[0]
    (tmp_path / "my_columns.py").write_text(block, encoding="utf-8")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, "my_columns", raising=False)


def read_csv(path: Path) -> list[dict[str, str]]:
    with path.open(encoding="utf-8") as handle:
        return list(csv.DictReader(handle))


def test_the_guide_column_is_written_live_and_recomputed_by_the_replay(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    docs_example(tmp_path, monkeypatch)
    asked = ["my_columns:in_touch", "robots_done", "robot_base_link", "base_links"]
    path = write_scenario(tmp_path, steps=40, metrics={"columns": asked})
    out = tmp_path / "run"
    assert main(["run", str(path), "--out", str(out), "--quiet", "--no-plots"]) == 0
    with (out / "metrics.csv").open(encoding="utf-8") as handle:
        header = next(csv.reader(handle))
    tail = ["in_touch", "robots_done", "base_link_A", "base_link_B", "base_links"]
    assert header[-5:] == tail
    rows = read_csv(out / "metrics.csv")
    assert all(0.0 <= float(r["in_touch"]) <= 1.0 for r in rows)
    assert any(float(r["in_touch"]) > 0 for r in rows)  # the base hears its robots
    for r in rows:  # the per-robot links add up to the count
        assert int(r["base_links"]) == int(r["base_link_A"]) + int(r["base_link_B"])
    assert main(["replay", str(out), "--metrics"]) == 0
    assert "identical" in capsys.readouterr().out


def test_asking_for_no_column_writes_the_default_header(tmp_path: Path) -> None:
    out = tmp_path / "run"
    assert main(["run", str(write_scenario(tmp_path, steps=3)), "--out", str(out), "--quiet"]) == 0
    with (out / "metrics.csv").open(encoding="utf-8") as handle:
        header = next(csv.reader(handle))
    assert header == Layout.of(["A", "B"], latest=False, faults=False).header()
    assert header[:3] == ["step", "explored", "known_at_base"]
    robots = ["distance_A", "distance_B", "state_A", "state_B", "base_contact_A"]
    assert header[-6:] == [*robots, "base_contact_B"]


@pytest.mark.parametrize(
    ("columns", "message"),
    [
        (["robots_dne"], "unknown metric column 'robots_dne'. Did you mean 'robots_done'"),
        (["explored"], "'explored' is a default column of metrics.csv"),
        (["base_links", "base_links"], "'base_links' is column 'base_links', named twice"),
        (["no_such_module:thing"], "cannot import 'no_such_module'"),
    ],
)
def test_a_wrong_column_name_is_a_clear_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], columns: list[str], message: str
) -> None:
    path = write_scenario(tmp_path, metrics={"columns": columns})
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err
    assert message in err and str(path) in err and "metrics.columns[" in err
    assert "Traceback" not in err


def test_a_column_from_an_entry_point_has_a_short_name_and_is_never_a_default(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    import mresim_phys.registry as registry_module

    @column("share_done", optional=False, register=False)
    def share_done(record: StepRecord) -> float:
        return sum(r.state == "done" for r in record.robots) / len(record.robots)

    class Point:
        name, value = "share_done", "a_package:share_done"

        def load(self) -> Any:
            return share_done

    monkeypatch.setattr(registry_module, "entry_points", lambda group: [Point()])
    monkeypatch.setattr(COLUMNS, "_classes", dict(COLUMNS._classes))
    monkeypatch.setattr(COLUMNS, "_discovered", False)
    monkeypatch.setattr(COLUMNS, "_from_entry_points", set())
    assert COLUMNS.get("share_done") is share_done
    assert "share_done" not in DEFAULTS and share_done not in COLUMNS.registered()
    layout = Layout.of(["A"], latest=False, faults=False, extra=["share_done"])
    assert layout.header()[-1] == "share_done"


def test_the_trackers_read_the_same_values_as_the_csv(tmp_path: Path) -> None:
    sim = Simulation.from_yaml(write_scenario(tmp_path, steps=60))
    layout = Layout.of([r.name for r in sim.robots], latest=False, faults=False)
    rows = [dict(zip(layout.header(), layout.row(r), strict=True)) for r in sim.iterate()]
    for threshold, step in sim.milestones.explored.items():
        first = next(
            (int(r["step"]) for r in rows if float(r["explored"]) >= float(threshold)), None
        )
        assert first == step
    assert [repr(v) for v in sim.curves.known_at_base] == [r["known_at_base"] for r in rows]
    assert sim.comm_totals.comm_bytes == sum(int(r["comm_bytes"]) for r in rows)
    assert value_of("alive", sim.record) == 2


def test_every_built_in_column_is_in_the_guide() -> None:
    text = GUIDE.read_text(encoding="utf-8")
    missing = [c.name for c in COLUMNS.registered() if f"`{c.name}`" not in text]
    assert missing == []


def test_a_column_needs_a_known_flag() -> None:
    with pytest.raises(ValueError, match="needs 'sometimes' is none of connected"):
        column("odd", needs="sometimes", register=False)(lambda r: 0)
