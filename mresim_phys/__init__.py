"""mresim_phys: multi-robot exploration in continuous space (a Python MRESim).

The simulation cycle, one module per phase (paper, Algorithm 1)::

    scenario/load/io -> build -> world -> sensing -> mapping -> frontiers
    -> planning -> planners/ -> strategies/ -> motion -> comms/ -> metrics -> recorders -> cli

Typical use::

    from mresim_phys import Simulation
    sim = Simulation.from_yaml("scenarios/01_quickstart.yaml")
    last = sim.run()
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from mresim_phys.comms import COMM_MODELS
    from mresim_phys.errors import MapError, MresimError, ScenarioError, UnknownPluginError
    from mresim_phys.metrics import StepRecord
    from mresim_phys.planning import PLANNERS
    from mresim_phys.scenario.load import load_scenario, validate_scenario
    from mresim_phys.scenario.schema import Scenario
    from mresim_phys.sim import Simulation
    from mresim_phys.strategies import STRATEGIES

# Where each public name lives: imported on first use (PEP 562), so that ``import
# mresim_phys`` (and the ``mresim`` command's start, see ``launch.py``) loads nothing heavy.
_PUBLIC = {
    "COMM_MODELS": "mresim_phys.comms",
    "MapError": "mresim_phys.errors",
    "MresimError": "mresim_phys.errors",
    "ScenarioError": "mresim_phys.errors",
    "UnknownPluginError": "mresim_phys.errors",
    "StepRecord": "mresim_phys.metrics",
    "PLANNERS": "mresim_phys.planning",
    "load_scenario": "mresim_phys.scenario.load",
    "validate_scenario": "mresim_phys.scenario.load",
    "Scenario": "mresim_phys.scenario.schema",
    "Simulation": "mresim_phys.sim",
    "STRATEGIES": "mresim_phys.strategies",
}


def __getattr__(name: str) -> Any:
    """A public name, imported from its module on first use."""
    module = _PUBLIC.get(name)
    if module is None:
        raise AttributeError(f"module 'mresim_phys' has no attribute {name!r}")
    value = getattr(import_module(module), name)
    globals()[name] = value
    return value


__all__ = [
    "COMM_MODELS",
    "PLANNERS",
    "STRATEGIES",
    "MapError",
    "MresimError",
    "Scenario",
    "ScenarioError",
    "Simulation",
    "StepRecord",
    "UnknownPluginError",
    "load_scenario",
    "validate_scenario",
]
__version__ = "0.1.0"
