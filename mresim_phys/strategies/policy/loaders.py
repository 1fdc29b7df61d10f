"""Trained policies (phase 0, input; called in phase 4): a callable named
``package.module:attribute``, or an ONNX file run by onnxruntime (the ``learn`` extra).

A policy takes one observation (``observe.py``: a dict of numpy arrays) and returns the
action. An ONNX model's inputs are matched to observation keys by name, each given a batch
axis of 1 and the input's element type; its first output is the action itself, or, with
choice actions, one score per slot: the best valid slot is taken (``action_mask``).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from mresim_phys.errors import ScenarioError
from mresim_phys.plugin import named_object

Policy = Callable[[dict[str, np.ndarray]], Any]
ONNX_TYPES = {"tensor(float)": np.float32, "tensor(double)": np.float64,
              "tensor(int64)": np.int64, "tensor(int32)": np.int32,
              "tensor(int8)": np.int8, "tensor(uint8)": np.uint8}  # fmt: skip


class PolicyLoadError(ScenarioError):
    """A policy reference or file that cannot be used (the message says why)."""


def load_callable(reference: str) -> Policy:
    """The callable ``reference`` ('package.module:attribute') names."""
    module, _, attribute = reference.partition(":")
    if not module or not attribute:
        raise PolicyLoadError(f"policy {reference!r}: give it as 'package.module:attribute'")
    try:
        found = named_object(reference)
    except (ImportError, AttributeError) as exc:
        raise PolicyLoadError(f"policy {reference!r} cannot be loaded: {exc}") from None
    if not callable(found):
        raise PolicyLoadError(f"policy {reference!r} is a {type(found).__name__}, not callable")
    return found  # type: ignore[no-any-return]


class OnnxPolicy:
    """An ONNX model run by onnxruntime on the CPU (module docstring)."""

    def __init__(self, path: Path, slots: int | None) -> None:
        try:
            import onnxruntime
        except ImportError:
            raise PolicyLoadError(
                f"onnx {path}: onnxruntime is not installed (pip install -e '.[learn]')"
            ) from None
        if not path.is_file():
            raise PolicyLoadError(f"onnx {path}: no such file")
        try:
            self.session = onnxruntime.InferenceSession(
                str(path), providers=["CPUExecutionProvider"]
            )
        except Exception as exc:  # onnxruntime's own errors for a broken file
            raise PolicyLoadError(f"onnx {path}: not a model onnxruntime can run ({exc})") from None
        self.inputs = [
            (i.name, ONNX_TYPES.get(i.type, np.float32)) for i in self.session.get_inputs()
        ]
        self.slots = slots
        self.path = path

    def __call__(self, observation: dict[str, np.ndarray]) -> Any:
        """The action for ``observation``."""
        missing = [name for name, _ in self.inputs if name not in observation]
        if missing:
            raise PolicyLoadError(
                f"onnx {self.path}: inputs {missing} are not observation keys"
                f" ({sorted(observation)})"
            )
        feed = {n: np.asarray(observation[n], dtype=t)[None] for n, t in self.inputs}
        out = np.asarray(self.session.run(None, feed)[0])[0]
        mask = observation.get("action_mask")
        if self.slots is not None and out.size == self.slots and mask is not None:
            scores = np.where(mask.astype(bool), out.reshape(-1), -np.inf)
            return int(np.argmax(scores))
        return out


def load_policy(policy: str | None, onnx: str | None, slots: int | None) -> Policy | None:
    """The policy a ``policy`` strategy's parameters name (None: an environment decides)."""
    if policy is not None:
        return load_callable(policy)
    if onnx is not None:
        return OnnxPolicy(Path(onnx), slots)
    return None
