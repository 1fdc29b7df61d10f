"""Strict input models (shared by every phase): the base of scenario models and plugin Params.

One place decides what a number in a scenario may be, for the schema and for every
plugin family's parameters alike (``PluginParams`` builds on :class:`Strict`):

* unknown keys are errors and validated values are immutable;
* every float is finite (``.inf`` and ``.nan`` are errors);
* ``true``/``false`` are not numbers: a YAML boolean given to a number field is an
  error (pydantic's lax mode would read ``speed: true`` as 1);
* every number lies within bounds: a field's own (``Field(le=...)``), else the
  generic ones of :func:`generic_bounds` (dBm fields within +-300, other floats
  within +-1e6, integers within +-1e9), so an absurd value is a mistake caught
  when the scenario is read instead of an overflow deep inside a run.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import Annotated, Any, Literal, get_args, get_origin

from annotated_types import Ge, Gt, Le, Lt
from pydantic import BaseModel, ConfigDict, ValidationInfo, field_validator
from pydantic.fields import FieldInfo
from pydantic_core import PydanticCustomError

__all__ = ["MAX_FLOAT", "MAX_INT", "UNIT_BOUNDS", "Strict", "bounds_text", "generic_bounds"]

MAX_FLOAT = 1e6  # largest magnitude of a float without bounds of its own
MAX_INT = 10**9  # largest magnitude of an integer without bounds of its own
UNIT_BOUNDS: dict[str, tuple[float, float]] = {
    "_dbm": (-300.0, 300.0),  # a power level in dBm
}

Bounds = tuple[float | None, float | None]


def takes_numbers_only(annotation: Any) -> bool:
    """Whether ``annotation`` holds ``int`` or ``float`` somewhere and admits no boolean.

    >>> takes_numbers_only(tuple[float, float]), takes_numbers_only(bool | str)
    (True, False)
    """
    found = _number_kinds(annotation)
    return "number" in found and "bool" not in found


def _number_kinds(annotation: Any) -> set[str]:
    """'number' if ``annotation`` contains int or float, 'bool' if it admits booleans."""
    if annotation is bool or annotation is Any:
        return {"bool"}
    if annotation in (int, float):
        return {"number"}
    if get_origin(annotation) is Literal:
        return {"bool"} if any(isinstance(v, bool) for v in get_args(annotation)) else set()
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return set()  # a nested model checks its own fields
    kinds: set[str] = set()
    for arg in get_args(annotation):
        if isinstance(arg, type) or get_origin(arg) is not None or arg is Any:
            kinds |= _number_kinds(arg)
    return kinds


def has_bool(value: Any) -> bool:
    """Whether ``value`` is a boolean or a list/tuple holding one (at any depth)."""
    if isinstance(value, bool):
        return True
    return isinstance(value, (list, tuple)) and any(has_bool(v) for v in value)


def has_bytes(value: Any) -> bool:
    """Whether ``value`` is bytes (YAML ``!!binary``) or a list/tuple holding some."""
    if isinstance(value, (bytes, bytearray)):
        return True
    return isinstance(value, (list, tuple)) and any(has_bytes(v) for v in value)


def numbers_in(value: Any) -> Iterator[int | float]:
    """The numbers in a validated value: itself, or the items of its lists and tuples."""
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        yield value
    elif isinstance(value, (list, tuple)):
        for item in value:
            yield from numbers_in(item)


def constraints(field: FieldInfo) -> list[Any]:
    """The field's own constraints, and those of the items of a list of them
    (``list[Annotated[int, Field(ge=0)]]``)."""
    found = list(field.metadata)
    for arg in get_args(field.annotation):
        if get_origin(arg) is Annotated:
            for extra in get_args(arg)[1:]:
                found += extra.metadata if isinstance(extra, FieldInfo) else [extra]
    return found


def own_bounds(field: FieldInfo) -> tuple[bool, bool]:
    """Whether the field sets its own (lower, upper) bound."""
    found = constraints(field)
    low = any(isinstance(m, (Ge, Gt)) for m in found)
    high = any(isinstance(m, (Le, Lt)) for m in found)
    return low, high


def generic_bounds(name: str, field: FieldInfo, integer: bool) -> Bounds:
    """The (low, high) a field's numbers must keep where the field sets no bound itself.

    A field named ``*_dbm`` is a power level (:data:`UNIT_BOUNDS`); any other number is
    within +-:data:`MAX_FLOAT` (floats) or +-:data:`MAX_INT` (integers).
    """
    limit: float = MAX_INT if integer else MAX_FLOAT
    low, high = next(
        (b for suffix, b in UNIT_BOUNDS.items() if name.endswith(suffix)), (-limit, limit)
    )
    has_low, has_high = own_bounds(field)
    return (None if has_low else low), (None if has_high else high)


def is_integer(annotation: Any) -> bool:
    """Whether a number field holds integers only (``int``, ``list[int]``, ...)."""
    text = str(annotation)
    return "int" in text and "float" not in text


def number_text(value: Any) -> str:
    """A bound as text: integers exactly, floats short (``1000000.0`` -> ``1e+06``)."""
    return str(value) if isinstance(value, int) else f"{float(value):g}"


def bounds_text(name: str, field: FieldInfo) -> str:
    """The bounds of a number field as text (``0 < x <= 1000``), '' for other fields."""
    if not takes_numbers_only(field.annotation):
        return ""
    low, high = generic_bounds(name, field, is_integer(field.annotation))
    found = constraints(field)
    lower = [f"{number_text(m.gt)} <" for m in found if isinstance(m, Gt)]
    lower += [f"{number_text(m.ge)} <=" for m in found if isinstance(m, Ge)]
    upper = [f"< {number_text(m.lt)}" for m in found if isinstance(m, Lt)]
    upper += [f"<= {number_text(m.le)}" for m in found if isinstance(m, Le)]
    lower += [] if low is None else [f"{number_text(low)} <="]
    upper += [] if high is None else [f"<= {number_text(high)}"]
    return " ".join([*lower, "x", *upper])


class Strict(BaseModel):
    """Base of every input model: unknown keys are errors, values are immutable, numbers
    are finite, bounded and never booleans (see the module docstring)."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    @field_validator("*", mode="before")
    @classmethod
    def _no_booleans_for_numbers(cls, value: Any, info: ValidationInfo) -> Any:
        """``speed: true`` is a mistake, not the number 1; YAML's ``!!binary`` is not text."""
        if has_bytes(value):
            raise PydanticCustomError("binary_value", "expected text or a number, not !!binary")
        name = info.field_name
        if name is not None and has_bool(value):
            field = cls.model_fields[name]
            if takes_numbers_only(field.annotation):
                raise PydanticCustomError("bool_for_number", "expected a number, not true or false")
        return value

    @field_validator("*", mode="after")
    @classmethod
    def _within_bounds(cls, value: Any, info: ValidationInfo) -> Any:
        """Every number finite and within the field's generic bounds."""
        name = info.field_name
        if name is None:
            return value
        field = cls.model_fields[name]
        for number in numbers_in(value):
            check_number(name, field, number)
        return value


def check_number(name: str, field: FieldInfo, number: float) -> None:
    """Raise a validation error if ``number`` is not finite or outside the generic bounds."""
    if not math.isfinite(number):
        raise PydanticCustomError("finite_number", "expected a finite number")
    low, high = generic_bounds(name, field, isinstance(number, int))
    if (low is not None and number < low) or (high is not None and number > high):
        raise PydanticCustomError(
            "number_out_of_bounds",
            "expected {bounds}; a number this far out is taken for a mistake",
            {"bounds": within_text(low, high)},
        )


def within_text(low: float | None, high: float | None) -> str:
    """``a number from -1e+06 to 1e+06``, ``a number of at most 1e+09``, ..."""
    if low is not None and high is not None:
        return f"a number from {number_text(low)} to {number_text(high)}"
    if high is not None:
        return f"a number of at most {number_text(high)}"
    return f"a number of at least {number_text(low)}"
