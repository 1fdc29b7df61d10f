"""Argument types of the ``mresim`` command line (output edge): numbers and lists, checked.

Standard library only (PyYAML, a base dependency, is imported when a ``--set`` value is
read): every command's parser is built without importing the simulator.
Each raises :class:`argparse.ArgumentTypeError` saying what was expected, which argparse
turns into a usage line and exit status 2.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import Any, TypeVar

T = TypeVar("T")


def whole_number(text: str, minimum: int) -> int:
    """``text`` as an integer >= ``minimum``, or an argparse error saying what was expected."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < minimum:
        raise argparse.ArgumentTypeError(f"expected a number >= {minimum}, got {value}")
    return value


def positive_int(text: str) -> int:
    """argparse type: an integer >= 1."""
    return whole_number(text, 1)


def positive_float(text: str) -> float:
    """argparse type: a number > 0."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not value > 0:
        raise argparse.ArgumentTypeError(f"expected a number > 0, got {text}")
    return value


def non_negative_int(text: str) -> int:
    """argparse type: an integer >= 0."""
    return whole_number(text, 0)


def comma_separated(text: str, parse: Callable[[str], T], expected: str) -> list[T]:
    """argparse helper: the comma-separated parts of ``text``, each parsed (at least one;
    else an error saying ``expected``, e.g. 'team sizes such as 4,8,16')."""
    values = [parse(part) for part in text.split(",") if part.strip()]
    if not values:
        raise argparse.ArgumentTypeError(f"expected {expected}, got {text!r}")
    return values


def scenario_setting(text: str) -> tuple[str, Any]:
    """argparse type: ``PATH=VALUE``, a scenario field by its dotted path and its value
    read as YAML (``team.radius=2``, ``team.strategy={name: frontier, params: {...}}``),
    for ``scenario.overrides.apply_overrides``."""
    import yaml  # a base dependency, imported only when a setting is given

    path, sep, value = text.partition("=")
    if not sep or not path.strip():
        raise argparse.ArgumentTypeError(f"expected PATH=VALUE, got {text!r}")
    try:
        return path.strip(), yaml.safe_load(value)
    except yaml.YAMLError as exc:
        raise argparse.ArgumentTypeError(f"{text!r}: the value is no YAML ({exc})") from None


def add_settings(parser: argparse.ArgumentParser, help_text: str) -> None:
    """Give ``parser`` the repeatable ``--set PATH=VALUE`` (:func:`scenario_setting`),
    read as ``args.set``: a list of (path, value)."""
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        type=scenario_setting,
        metavar="PATH=VALUE",
        help=help_text,
    )
