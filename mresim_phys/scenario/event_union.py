"""Scenario schema, the events (phase 0, input): an ``events[i]`` entry validated by the
``Params`` of the registered event whose key it holds.

The union of every registered event's ``Params`` is built from the registry when an entry
is validated (an event registered in code or by an entry point since the last scenario is
known at once; nothing is rebuilt), and a lazily entered built-in is validated without
importing what it does.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Annotated, Any, Union

from pydantic import (
    Discriminator,
    SerializeAsAny,
    Tag,
    TypeAdapter,
    ValidatorFunctionWrapHandler,
    WrapValidator,
)

from mresim_phys.world.event_catalog import EVENTS
from mresim_phys.world.event_params import EventParams


def event_params(name: str) -> type[EventParams]:
    """The ``Params`` model of registered event ``name`` (without importing a built-in
    event's implementation)."""
    model = EVENTS.params_model(name)
    assert model is not None and issubclass(model, EventParams)  # the event family's rule
    return model


def event_kind(value: Any) -> str | None:
    """Which registered event a YAML entry is: the first event name among its keys."""
    if isinstance(value, EventParams):
        return next((n for n in EVENTS.names() if isinstance(value, event_params(n))), None)
    if isinstance(value, dict):
        return next((n for n in EVENTS.names() if n in value), None)
    return None


@lru_cache(maxsize=8)
def event_adapter(names: tuple[str, ...]) -> TypeAdapter[Any]:
    """A validator of one ``events[i]`` entry: one tagged member per registered event's
    ``Params`` (``names``: the registry's event names when it is asked)."""
    members = tuple(Annotated[event_params(n), Tag(n)] for n in names)
    union: Any = Annotated[
        Union[members],  # noqa: UP007 (a union built from a tuple of types)
        Discriminator(
            event_kind,
            custom_error_type="unknown_event",
            custom_error_message="an event needs one of the keys "
            + ", ".join(repr(n) for n in names),
        ),
    ]
    return TypeAdapter(union)


def validate_event(value: Any, handler: ValidatorFunctionWrapHandler) -> EventParams:
    """One ``events[i]`` entry validated by the ``Params`` of its event, looked up in the
    registry now (an event registered in code or by an entry point since the last
    scenario is known at once; nothing is rebuilt)."""
    if isinstance(value, EventParams):
        return value
    event: EventParams = event_adapter(tuple(EVENTS.names())).validate_python(value)
    return event


EventList = list[SerializeAsAny[Annotated[EventParams, WrapValidator(validate_event)]]]
