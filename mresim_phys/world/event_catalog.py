"""The event registry (phase 0, input): built-in event keys, their parameters, lazy classes.

Importing this module imports no event: each built-in is entered with its ``Params`` model
(:mod:`mresim_phys.world.event_params`) and a ``module:Class`` reference to its class in
``world/events.py``, imported when a run builds its events. Third-party events register
through the ``mresim_phys.events`` entry-point group or are named as
``package.module:ClassName``; the scenario schema validates an entry against the model of
the key that marks it (``{step: 300, fail: B}`` is a ``fail`` event).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from pydantic import BaseModel

from mresim_phys.plugin import Family
from mresim_phys.registry import Registry
from mresim_phys.world import event_params as p

if TYPE_CHECKING:
    from mresim_phys.world.event_api import Event

EVENTS: Registry[Event] = Registry(
    "event", "mresim_phys.events", Family("mresim_phys.world.event_api:Event", p.EventParams)
)
BUILT_IN: dict[str, tuple[str, type[BaseModel]]] = {
    "fail": ("Failure", p.FailParams),
    "blackout": ("Blackout", p.BlackoutParams),
    "cells": ("Cells", p.CellsParams),
    "collapse": ("Collapse", p.CollapseParams),
    "close": ("Close", p.CloseParams),
    "open": ("Open", p.OpenParams),
}
EVENTS.enter("mresim_phys.world.events:", BUILT_IN)
