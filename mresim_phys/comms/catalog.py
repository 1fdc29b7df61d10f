"""The comm-model registry (phase 0, input): built-in names, their parameters, lazy classes.

Importing this module imports no comm model: each built-in is entered with its ``Params``
model (:mod:`mresim_phys.comms.params`) and a ``module:Class`` reference to its class,
imported when a run builds its radios. Third-party models register through the
``mresim_phys.comm_models`` entry-point group or are named as ``package.module:ClassName``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from pydantic import BaseModel

from mresim_phys.comms import params as p
from mresim_phys.plugin import Family
from mresim_phys.registry import Registry

if TYPE_CHECKING:
    from mresim_phys.comms.base import CommModel

COMM_MODELS: Registry[CommModel] = Registry(
    "communication model",
    "mresim_phys.comm_models",
    Family("mresim_phys.comms.base:CommModel", p.CommParams),
)
BUILT_IN: dict[str, tuple[str, type[BaseModel]]] = {
    "disk": ("disk:DiskComm", p.DiskParams),
    "line_of_sight": ("line_of_sight:LineOfSightComm", p.LineOfSightParams),
    "path_loss": ("path_loss:PathLossComm", p.PathLossParams),
}
COMM_MODELS.enter("mresim_phys.comms.", BUILT_IN)
