"""Composition root (between input and runtime): a validated Scenario -> runtime values.

The runtime reaches the input side only through here: ``load_scenario`` (a YAML
file -> a validated, picklable ``Scenario``) and ``build_setup`` (a Scenario ->
the runtime values a ``Simulation`` runs on).
"""

from __future__ import annotations

from mresim_phys.build.network import build_network, region_probe
from mresim_phys.build.setup import RunRules, Setup, build_setup
from mresim_phys.scenario.load import load_scenario
from mresim_phys.scenario.schema import Scenario

__all__ = [
    "RunRules",
    "Scenario",
    "Setup",
    "build_network",
    "build_setup",
    "load_scenario",
    "region_probe",
]
