"""Scenario faults (loading, before phase 0): which parts of a scenario make robots fail.

One place says what a fault is, for two users: the metrics file of a paired run with
faults gets the robustness columns (``robustness_columns``), and ``mresim run --paired`` (or
``simulation.paired: true``) runs the baseline of the same scenario and seed with every
fault switched off (``without_faults``). Today the faults are the scheduled ``fail`` events
(any part); fault models added later (random failures, batteries, hazard zones) belong
here too, so the baseline switches them off as well. Other events (blackouts, collapses,
doors) are part of the world, not faults, and stay in the baseline; a collapse that buries
a robot is therefore not switched off. The events' random streams are numbered by their
place in ``events``, so removing a fail event renumbers the streams of the events after
it (no shipped event draws from its stream).
"""

from __future__ import annotations

from mresim_phys.scenario.schema import Scenario
from mresim_phys.world.event_params import FailParams


def fault_events(scenario: Scenario) -> list[FailParams]:
    """The scenario's scheduled failures."""
    return [e for e in scenario.events if isinstance(e, FailParams)]


def has_faults(scenario: Scenario) -> bool:
    """Whether anything in ``scenario`` makes a robot (or a part of one) fail."""
    return bool(fault_events(scenario)) or scenario.faults is not None


def localization_faults(scenario: Scenario) -> set[str]:
    """The robots a localisation fault (a ``fail`` event or a random law or hazard of the
    ``faults:`` block with part ``localization``) may strike."""
    names = [r.name for r in scenario.robots]
    struck = {e.fail for e in fault_events(scenario) if e.part == "localization"}
    faults = scenario.faults
    laws = [*faults.random, *faults.hazards] if faults is not None else []
    for law in laws:
        if law.part == "localization":
            struck |= set(names) if law.robots == "all" else set(law.robots)
    return struck


def has_localization(scenario: Scenario) -> bool:
    """Whether a robot of ``scenario`` has localisation: a ``localization:`` block, or a
    localisation fault that may strike it (metrics.csv then has the pose columns)."""
    return any(r.localization is not None for r in scenario.robots) or bool(
        localization_faults(scenario)
    )


def robustness_columns(scenario: Scenario) -> bool:
    """Whether ``metrics.csv`` gets the robustness columns: in a paired run (which has
    faults). Other runs keep their columns, so the results of scenarios written before
    these columns existed stay byte for byte the same; their failures are in summary.json."""
    return scenario.simulation.paired and has_faults(scenario)


def paired_problem(scenario: Scenario) -> str | None:
    """Why ``scenario`` cannot be a paired run (None: it can, or it is not paired)."""
    if not scenario.simulation.paired or has_faults(scenario):
        return None
    return (
        f"scenario {scenario.name!r} asks for a paired run (--paired or simulation.paired:"
        " true), but it has no faults to switch off: no 'fail' events and no 'faults' block,"
        " so the baseline would be the same run. Add failures (e.g. events: [{step: 300,"
        " fail: B}] or faults: {random: [{mtbf: 800}]}) or run it without --paired /"
        " simulation.paired."
    )


def without_faults(scenario: Scenario) -> Scenario:
    """``scenario`` with every fault switched off (and no baseline of its own)."""
    events = [e for e in scenario.events if not isinstance(e, FailParams)]
    simulation = scenario.simulation.model_copy(update={"paired": False})
    return scenario.model_copy(update={"events": events, "faults": None, "simulation": simulation})
