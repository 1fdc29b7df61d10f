"""Communication (phase 6): comm models (a plugin family) and knowledge exchange.

Importing the package is light: :data:`COMM_MODELS` (``catalog``) holds every built-in by
name, with its ``Params`` model (``params``) and a reference to its class, imported when a
run builds its radios. ``CommModel`` and ``Radios`` come from ``base`` on first use.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

from mresim_phys.comms.catalog import BUILT_IN, COMM_MODELS
from mresim_phys.comms.params import CommParams

if TYPE_CHECKING:
    from mresim_phys.comms.base import CommModel, Radios

INTERFACE = ("CommModel", "Radios")  # from base, on first use


def __getattr__(name: str) -> object:
    """The comm interface's names, imported from ``base`` when first asked for."""
    if name in INTERFACE:
        return getattr(importlib.import_module("mresim_phys.comms.base"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["BUILT_IN", "COMM_MODELS", "CommModel", "CommParams", "Radios"]
