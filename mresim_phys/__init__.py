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

from mresim_phys.comms import COMM_MODELS
from mresim_phys.errors import MapError, MresimError, ScenarioError, UnknownPluginError
from mresim_phys.metrics import StepRecord
from mresim_phys.planning import PLANNERS
from mresim_phys.scenario.load import load_scenario, validate_scenario
from mresim_phys.scenario.schema import Scenario
from mresim_phys.sim import Simulation
from mresim_phys.strategies import STRATEGIES

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
