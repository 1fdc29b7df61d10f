"""Radio options checked against the rest of the scenario (phase 0, input).

A channel's radio options (``comms/radio_params.py``) are checked alone by the schema;
here the parts that need the scenario or its folder: shadowing needs a comm model with a
signal in dB, a bounded link needs map deltas, and the trace and loss-table files are made
absolute (relative paths are to the scenario file) and read once, so a wrong file is a
one-paragraph error when the scenario is loaded, not a traceback when the run is built.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

from mresim_phys.comms import BUILT_IN, COMM_MODELS
from mresim_phys.comms.traces import TraceError, check_loss_table, loss_rows, trace_rows
from mresim_phys.errors import ScenarioError
from mresim_phys.knowledge.teammates import BASE_NAME
from mresim_phys.scenario.schema import ChannelSpec, Scenario

C = TypeVar("C", bound=ChannelSpec)
SIGNAL_MODELS = ("path_loss",)  # the built-in comm models with a signal in dB


def resolve_radio(scenario: Scenario, folder: Path, source: str) -> Scenario:
    """The scenario with each channel's radio files absolute and every radio option checked."""
    names = [BASE_NAME, *(r.name for r in scenario.robots)]
    comm = scenario.communication
    if comm.maps == "full" and comm.bounded:
        raise ScenarioError(
            f"{source}: communication.maps: 'full' sends whole grids and cannot be queued on a"
            " link with a capacity or a latency; use maps: delta (the default) with them."
        )
    main = resolve_channel(comm, folder, source, "communication", names)
    control = comm.control
    if control is not None:
        where = "communication.control"
        control = resolve_channel(control, folder, source, where, names)
    comm = main.model_copy(update={"control": control})
    return scenario.model_copy(update={"communication": comm})


def resolve_channel(channel: C, folder: Path, source: str, where: str, names: list[str]) -> C:
    """``channel`` with its trace and loss-table paths absolute, both read and checked."""
    if channel.shadowing is not None and not has_signal(channel.model):
        raise ScenarioError(
            f"{source}: {where}.shadowing: the comm model {channel.model!r} has no signal in dB"
            " for shadowing to add to; use model: path_loss (or a model with pair_signals)."
        )
    update: dict[str, object] = {}
    if channel.trace is not None:
        trace = _absolute(channel.trace, folder)
        _read(lambda: trace_rows(str(trace), names), source, f"{where}.trace", trace)
        update["trace"] = str(trace)
    table = channel.loss_table
    if table is not None:
        path = _absolute(table, folder) if isinstance(table, str) else None
        rows = table if path is None else str(path)
        _read(lambda: check_loss_table(loss_rows(rows)), source, f"{where}.loss_table", path)
        if path is not None:
            update["loss_table"] = str(path)
    return channel.model_copy(update=update)


def has_signal(model: str) -> bool:
    """Whether comm model ``model`` gives a signal in dB (``pair_signals``): the built-ins
    are known by name (validating imports no comm model); a plugin's class is asked."""
    if model in BUILT_IN:
        return model in SIGNAL_MODELS
    return hasattr(COMM_MODELS.get(model), "pair_signals")


def _absolute(value: str, folder: Path) -> Path:
    """``value`` as an absolute path (relative to the scenario's folder)."""
    return (folder / Path(value).expanduser()).resolve()


def _read(check: Callable[[], object], source: str, where: str, path: Path | None) -> None:
    """Run ``check``; a TraceError becomes a ScenarioError naming ``where``."""
    try:
        check()
    except (TraceError, OSError, ValueError) as exc:
        shown = f" ({path})" if path is not None else ""
        raise ScenarioError(
            f"{source}: {where}{shown}: {exc}. See docs/communication.md, 'Radio links'."
        ) from None
