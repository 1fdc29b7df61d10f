"""Communication (phase 6): comm models (a plugin family) and knowledge exchange."""

from __future__ import annotations

from mresim_phys.comms import disk, line_of_sight, path_loss
from mresim_phys.comms.base import COMM_MODELS, CommModel, CommParams, Radios

BUILT_IN = ("disk", "line_of_sight", "path_loss")
assert {disk.DiskComm.name, line_of_sight.LineOfSightComm.name, path_loss.PathLossComm.name} == set(
    BUILT_IN
)

__all__ = ["BUILT_IN", "COMM_MODELS", "CommModel", "CommParams", "Radios"]
