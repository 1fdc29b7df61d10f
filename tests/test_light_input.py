"""The light input layer (issue 30, part 4): parameter models in modules of pydantic and the
standard library, registries that enter built-ins by reference, and ``mresim validate``
without numba, pymunk or OpenCV."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
import yaml

from mresim_phys.cli import BENCH_PRESETS, main
from mresim_phys.comms.catalog import COMM_MODELS
from mresim_phys.errors import UnknownPluginError
from mresim_phys.planning.catalog import PLANNERS
from mresim_phys.plugin import Family, PluginParams
from mresim_phys.registry import Registry
from mresim_phys.strategies.catalog import STRATEGIES
from mresim_phys.world.event_catalog import EVENTS

REPO = Path(__file__).resolve().parent.parent
SCENARIOS = sorted((REPO / "scenarios").glob("*.yaml"))
HEAVY = ("numba", "pymunk", "cv2")
LIGHT_MODULES = (  # parameter models and registries: pydantic and the standard library only
    "mresim_phys.strategies.params",
    "mresim_phys.strategies.catalog",
    "mresim_phys.planning.params",
    "mresim_phys.planning.catalog",
    "mresim_phys.comms.params",
    "mresim_phys.comms.catalog",
    "mresim_phys.world.event_params",
    "mresim_phys.world.event_catalog",
    "mresim_phys.world.event_api",
    "mresim_phys.world.element_params",
    "mresim_phys.world.shapes",
    "mresim_phys.faults.spec",
    "mresim_phys.scenario.maps",
    "mresim_phys.scenario.schema",
    "mresim_phys.scenario.run_specs",
    "mresim_phys.scenario.event_union",
)
NOT_STDLIB = ("numpy", "scipy", "numba", "pymunk", "cv2", "skimage", "shapely", "PIL", "yaml")


def imported_after(code: str) -> dict[str, object]:
    """Run ``code`` in a fresh interpreter; return its ``result`` and the top-level packages
    it had imported."""
    probe = (
        f"import sys, json\n{code}\n"
        "print(json.dumps({'result': result, 'modules': sorted({m.split('.')[0] for m in"
        " sys.modules})}))"
    )
    done = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, timeout=120, cwd=REPO
    )
    assert done.returncode == 0, done.stderr
    found: dict[str, object] = json.loads(done.stdout.splitlines()[-1])
    return found


def test_validating_every_shipped_scenario_imports_no_simulator() -> None:
    paths = [str(p) for p in SCENARIOS]
    found = imported_after(
        f"from mresim_phys.cli import main\nresult = [main(['validate', p]) for p in {paths!r}]"
    )
    assert found["result"] == [0] * len(SCENARIOS)
    modules = found["modules"]
    assert isinstance(modules, list)
    assert [m for m in HEAVY if m in modules] == []


@pytest.mark.parametrize("module", LIGHT_MODULES)
def test_parameter_models_need_only_pydantic(module: str) -> None:
    found = imported_after(f"import {module}\nresult = None")
    modules = found["modules"]
    assert isinstance(modules, list)
    assert [m for m in NOT_STDLIB if m in modules] == []


def test_the_command_line_parser_is_light() -> None:
    found = imported_after(
        "from mresim_phys.cli import make_parser\n"
        "result = make_parser().parse_args(['bench', '--strategies', 'frontier']).command"
    )
    assert found["result"] == "bench"
    modules = found["modules"]
    assert isinstance(modules, list)
    assert [m for m in (*HEAVY, "tqdm", "scipy") if m in modules] == []


@pytest.mark.parametrize("registry", [STRATEGIES, PLANNERS, COMM_MODELS, EVENTS])
def test_a_lazy_builtin_is_the_class_it_names_with_its_params(registry: Registry[object]) -> None:
    for name in registry.names():
        entered = registry.params_model(name)
        cls: Any = registry.get(name)  # imports the implementation, which registers itself
        assert cls.name == name
        assert cls.Params is entered


@pytest.mark.parametrize(
    ("catalog", "registry", "name"),
    [
        ("strategies.catalog", "STRATEGIES", "frontier"),
        ("planning.catalog", "PLANNERS", "jps"),
        ("comms.catalog", "COMM_MODELS", "path_loss"),
        ("world.event_catalog", "EVENTS", "collapse"),
    ],
)
def test_a_lazy_builtin_loads_in_a_fresh_interpreter(
    catalog: str, registry: str, name: str
) -> None:
    found = imported_after(
        f"from mresim_phys.{catalog} import {registry}\nresult = {registry}.get({name!r}).name"
    )
    assert found["result"] == name


def test_a_class_unlike_its_lazy_entry_is_refused() -> None:
    class Probe:
        """A protocol of one method."""

        def act(self) -> None:
            """Act."""

    registry: Registry[object] = Registry("probe", "none.probes", Family(Probe, PluginParams))
    registry.lazy("walk", "somewhere.else:Walker", PluginParams)

    class Walker:
        name = "walk"
        Params = PluginParams

        def act(self) -> None:
            """Act."""

    with pytest.raises(ValueError, match=r"entered as 'somewhere\.else:Walker'"):
        registry.register(Walker)
    with pytest.raises(ValueError, match="already registered"):
        registry.lazy("walk", "x:Y", PluginParams)


def test_an_unknown_plugin_still_names_the_lazy_builtins() -> None:
    with pytest.raises(UnknownPluginError, match="Did you mean 'frontier'"):
        STRATEGIES.params_model("fronteer")


def test_bench_presets_named_by_the_parser_are_the_bench_presets() -> None:
    from mresim_phys.output.bench import PRESETS

    assert set(BENCH_PRESETS) == set(PRESETS)


def shifted_start_scenario(tmp_path: Path) -> Path:
    """The quickstart with robot A's centre on a free cell but its body over a wall."""
    data = yaml.safe_load((REPO / "scenarios" / "01_quickstart.yaml").read_text())
    data["map"]["image"] = str(REPO / "maps" / "small_rooms.png")
    data["robots"][0]["start"] = [2.5, 2.5]  # a free cell by the map's 2-cell wall, radius 2
    path = tmp_path / "shifted.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_validate_checks_the_grid_and_explorable_checks_the_exact_walls(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = shifted_start_scenario(tmp_path)
    assert main(["validate", str(path)]) == 0
    out = capsys.readouterr().out
    assert "left to --explorable" in out and "clearance from the exact walls" in out
    assert main(["validate", "--explorable", str(path)]) == 2
    err = capsys.readouterr().err
    assert "inside or overlapping a wall" in err and str(path) in err


@pytest.mark.parametrize(
    ("change", "words"),
    [
        ({"start": [-3, 5]}, "outside the"),
        ({"start": [0.5, 0.5]}, "inside or overlapping a wall"),
    ],
)
def test_validate_refuses_a_start_off_the_free_cells(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], change: dict[str, object], words: str
) -> None:
    data = yaml.safe_load((REPO / "scenarios" / "01_quickstart.yaml").read_text())
    data["map"]["image"] = str(REPO / "maps" / "small_rooms.png")
    data["robots"][0].update(change)
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(data))
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err
    assert words in err and str(path) in err and "robot 'A'" in err
