"""Communication (phase 6): comm models (a plugin family) and knowledge exchange."""

from __future__ import annotations

from . import disk
from .base import COMM_MODELS, CommModel, CommParams

BUILT_IN = ("disk",)
assert {disk.DiskComm.name} == set(BUILT_IN)

__all__ = ["BUILT_IN", "COMM_MODELS", "CommModel", "CommParams"]
