"""User-facing errors: every mistake a user can make ends in one of these.

The CLI catches :class:`MresimError` and prints its message (one paragraph, no
traceback) with a non-zero exit status. Anything else escaping is a bug.
"""

from __future__ import annotations


class MresimError(Exception):
    """A mistake in user input (scenario, map, command line) with a readable message."""


class ScenarioError(MresimError):
    """The scenario YAML is malformed or fails validation."""


class MapError(MresimError):
    """A map file is missing, unreadable or malformed."""


class UnknownPluginError(MresimError, KeyError):
    """A strategy or communication model name that no registry knows."""

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


class UnknownRobotError(MresimError, KeyError):
    """A robot name that the run's team does not have (``Simulation.robot``)."""

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""
