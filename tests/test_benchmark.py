"""``mresim benchmark`` (``sweeps/benchmark.py``): a suite drawn, swept and tabulated with
its hashes; ``--check`` confirms the runs byte for byte and fails on a doctored file."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pytest
import yaml

from mresim_phys.cli import main


def write_suite(folder: Path, **fields: object) -> Path:
    (folder / "set.yaml").write_text(
        yaml.safe_dump(
            {
                "name": "tiny",
                "instances": [
                    {"kind": "building", "size": [160, 120], "seeds": 2},
                    {
                        "kind": "blueprint",
                        "size": [160, 120],
                        "params": {"shape": "loop"},
                        "seeds": [0],
                    },
                ],
                "split": {"test": 0.34, "seed": 0},
            }
        )
    )
    suite = {
        "name": "tiny",
        "instances": "set.yaml",
        "strategies": ["frontier", "nearest_frontier"],
        "seeds": 1,
        "steps": 120,
        "metrics": {"team": True, "budget": {"explored": 0.9, "within": 100}},
        **fields,
    }
    path = folder / "suite.yaml"
    path.write_text(yaml.safe_dump(suite))
    return path


@pytest.fixture(scope="module")
def results(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("bench")
    out = folder / "out"
    args = ["benchmark", str(write_suite(folder)), "--out", str(out), "--workers", "1", "--quiet"]
    assert main(args) == 0
    return out


def test_a_suite_writes_its_table_and_its_hashes(results: Path) -> None:
    table = pd.read_parquet(results / "results.parquet")
    assert len(table) == 6  # 3 instances x 2 strategies x 1 seed
    assert set(table["kind"]) == {"building", "blueprint"}
    assert {"success", "overlap", "workload_cv", "steps_to_explored_90"} <= set(table.columns)
    record = json.loads((results / "results.json").read_text())
    assert len(record["instances"]) == 3 and len(record["runs"]) == 6
    assert record["packages"]["numpy"] != "unknown"
    assert record["processor"]["machine"] and isinstance(record["processor"]["simd"], list)
    index = yaml.safe_load((results / "instances" / "set.yaml").read_text())
    assert record["instances"] == {i["id"]: i["grid_sha256"] for i in index["instances"]}
    page = (results / "results.md").read_text()
    assert "| building | frontier | 4 | 0 | 2 |" in page and "Kaplan-Meier" in page


def test_check_confirms_the_runs_and_fails_on_a_doctored_file(
    results: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["benchmark", "--check", str(results), "--sample", "2"]) == 0
    doctored = tmp_path / "doctored"
    import shutil

    shutil.copytree(results, doctored)
    record = json.loads((doctored / "results.json").read_text())
    first = sorted(record["runs"])[0]
    record["runs"][first]["metrics_sha256"] = "0" * 64
    (doctored / "results.json").write_text(json.dumps(record))
    capsys.readouterr()
    assert main(["benchmark", "--check", str(doctored), "--sample", "0"]) == 1
    err = capsys.readouterr().err
    assert first in err and "other vector extensions" not in err
    record["processor"]["simd"] = ["ANOTHER_PROCESSOR"]  # as if recorded elsewhere
    (doctored / "results.json").write_text(json.dumps(record))
    assert main(["benchmark", "--check", str(doctored), "--sample", "0"]) == 1
    assert "other vector extensions than this one" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("fields", "named"),
    [({"strategies": []}, "strategies"), ({"split": "half"}, "split"), ({"seeds": 0}, "seeds")],
)
def test_a_bad_suite_is_one_paragraph_naming_the_field_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], fields: dict[str, object], named: str
) -> None:
    path = write_suite(tmp_path, **fields)
    assert main(["benchmark", str(path), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert named in err and "suite.yaml" in err and "Traceback" not in err
