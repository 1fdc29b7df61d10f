"""Procedural maps (phase 0, input): a validation error as one line naming the parameter."""

from __future__ import annotations

from pydantic import ValidationError


def describe(exc: ValidationError) -> str:
    """The first validation error as one line naming the parameter (``--set NAME``)."""
    first = exc.errors()[0]
    name = ".".join(str(part) for part in first["loc"]) or "parameters"
    message = str(first["msg"]).removeprefix("Value error, ")
    return f"{name}: {message} (see docs/procedural-maps.md for each kind's parameters)"
