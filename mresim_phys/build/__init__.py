"""Composition root (between input and runtime): a validated Scenario -> runtime values."""

from __future__ import annotations

from mresim_phys.build.network import build_network, region_probe
from mresim_phys.build.setup import RunRules, Setup, build_setup

__all__ = ["RunRules", "Setup", "build_network", "build_setup", "region_probe"]
