"""Phase 0 (input edge): YAML files read safely, as untrusted input.

Every YAML the project reads (scenarios, studies, ROS map files, team files, a run's
recorded scenario) goes through :func:`parse_yaml`: PyYAML's safe loader (no arbitrary
objects), a key given twice in one mapping is an error, and the document is refused
before any value is built when it is bigger than a user's file can honestly be:

* the file is larger than :data:`MAX_YAML_BYTES`;
* its aliases (``*name``) would add more than :data:`MAX_ALIAS_VALUES` values once
  expanded (a "billion laughs" alias bomb: 1.5 KB of text that expands to 10^9 values
  spins any code that walks it), or an alias refers to the mapping or list that holds
  it (a loop: no finite value).

Every problem ends in the caller's error type (a :class:`~mresim_phys.errors.ScenarioError`
or :class:`~mresim_phys.errors.MapError`) whose one-paragraph message names the file.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import yaml

from mresim_phys.errors import MresimError, ScenarioError

__all__ = [
    "MAX_ALIAS_VALUES",
    "MAX_YAML_BYTES",
    "YamlSizeError",
    "parse_yaml",
    "read_yaml_file",
    "read_yaml_mapping",
    "require_file",
]

MAX_YAML_BYTES = 32 * 1024 * 1024  # a scenario or study is kilobytes; 32 MB is no user file
MAX_ALIAS_VALUES = 100_000  # values aliases may add once expanded (a robot list x 1000 is 10^4)


class YamlSizeError(yaml.YAMLError):
    """A document whose aliases expand past :data:`MAX_ALIAS_VALUES`, or loop."""


def require_file(path: Path, what: str, error: type[MresimError]) -> Path:
    """Return ``path`` if it is an existing regular file, else raise ``error`` with a fix.

    A directory, a FIFO or a device (``/dev/zero``) is refused here, before any read.
    """
    if not path.exists():
        raise error(f"{what} {path} does not exist. Check the path and its spelling.")
    if not path.is_file():
        raise error(
            f"{what} {path} is not a regular file (a directory, a pipe or a device?)."
            " Give the path of a file."
        )
    return path


def expanded_size(root: yaml.Node) -> tuple[int, int]:
    """How many values ``root`` holds once every alias is expanded, and how many distinct
    nodes it is made of (a loop: YamlSizeError).

    Aliases share their node, so the count is memoised per node; the walk is iterative
    (a deeply nested document must not exhaust the stack here).
    """
    sizes: dict[int, int] = {}
    open_nodes: set[int] = set()
    stack: list[tuple[yaml.Node, bool]] = [(root, False)]
    while stack:
        node, children_done = stack.pop()
        if id(node) in sizes:
            continue
        children = _children(node)
        if children_done:
            open_nodes.discard(id(node))
            sizes[id(node)] = 1 + sum(sizes[id(child)] for child in children)
            continue
        if id(node) in open_nodes:
            raise YamlSizeError(_loop_message(node))
        open_nodes.add(id(node))
        stack.append((node, True))
        for child in children:
            if id(child) in open_nodes:
                raise YamlSizeError(_loop_message(child))
            stack.append((child, False))
    return sizes[id(root)], len(sizes)


def _children(node: yaml.Node) -> list[yaml.Node]:
    if isinstance(node, yaml.SequenceNode):
        return list(node.value)
    if isinstance(node, yaml.MappingNode):
        return [part for pair in node.value for part in pair]
    return []


def _loop_message(node: yaml.Node) -> str:
    line = node.start_mark.line + 1 if node.start_mark else "?"
    return (
        f"an alias at or inside the value starting at line {line} refers to a value that"
        " contains it (a loop with no end); write the value out instead"
    )


def check_alias_expansion(root: yaml.Node) -> None:
    """Refuse a document whose aliases add more than :data:`MAX_ALIAS_VALUES` values."""
    expanded, distinct = expanded_size(root)
    added = expanded - distinct
    if added > MAX_ALIAS_VALUES:
        raise YamlSizeError(
            f"its aliases (*name) expand to {added:,} more values, over the limit of"
            f" {MAX_ALIAS_VALUES:,} (an alias bomb?); write the values out or use fewer aliases"
        )


class UniqueKeyLoader(yaml.SafeLoader):
    """PyYAML's safe loader, except that a key given twice in one mapping is an error.

    Plain PyYAML keeps the last of two ``seed:`` lines silently; here the second one is
    a :class:`yaml.constructor.ConstructorError` naming the key and both lines. Keys
    merged in with ``<<: *anchor`` may still be overridden, as YAML intends. A document
    whose aliases expand too far is refused before any value is built.
    """

    def construct_document(self, node: yaml.Node) -> Any:
        check_alias_expansion(node)
        return super().construct_document(node)

    def construct_mapping(self, node: yaml.Node, deep: bool = False) -> dict[Any, Any]:
        if isinstance(node, yaml.MappingNode):
            self._check_unique_keys(node)
        return super().construct_mapping(node, deep=deep)  # type: ignore[arg-type]

    def construct_object(self, node: yaml.Node, deep: bool = False) -> Any:
        """A value, or a ConstructorError at its line (PyYAML raises a bare ValueError
        for an impossible date such as ``2001-13-01``)."""
        try:
            return super().construct_object(node, deep=deep)
        except (ValueError, TypeError, OverflowError) as exc:
            what = f" {node.value!r}" if isinstance(node, yaml.ScalarNode) else ""
            raise yaml.constructor.ConstructorError(
                None, None, f"cannot read the value{what}: {exc}", node.start_mark
            ) from None

    def _check_unique_keys(self, node: yaml.MappingNode) -> None:
        seen: dict[Any, yaml.Node] = {}
        for key_node, _ in node.value:
            if not isinstance(key_node, yaml.ScalarNode) or key_node.tag.endswith(":merge"):
                continue
            key = self.construct_object(key_node)
            try:
                first = seen.setdefault(key, key_node)
            except TypeError:  # an unhashable key: the base loader reports it
                continue
            if first is not key_node:
                raise yaml.constructor.ConstructorError(
                    "while reading a mapping",
                    node.start_mark,
                    f"key {key!r} appears twice (first at line {first.start_mark.line + 1});"
                    " keep only one",
                    key_node.start_mark,
                )


def parse_yaml(text: str) -> Any:
    """The YAML document in ``text``, read safely with :class:`UniqueKeyLoader`."""
    return yaml.load(text, Loader=UniqueKeyLoader)  # a SafeLoader: no arbitrary objects


def _yaml_problem(exc: Exception) -> str:
    """What went wrong reading YAML, as the end of a sentence: ``' at line 3, ...: ...'``."""
    if isinstance(exc, RecursionError):
        return ": it is nested too deeply to read (thousands of levels); flatten it"
    if isinstance(exc, YamlSizeError):
        return f": {exc}"
    if not isinstance(exc, yaml.YAMLError):  # e.g. a date like 2001-13-01
        return f": {type(exc).__name__}: {exc}; fix that value"
    mark = getattr(exc, "problem_mark", None)
    where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
    problem = getattr(exc, "problem", None) or str(exc)
    if isinstance(exc, yaml.constructor.ConstructorError):
        return f"{where}: {problem}"
    return f"{where}: {problem}. Fix the syntax there (indentation, ':' after keys, quotes)"


def _read_text(path: Path, what: str, error: type[MresimError]) -> str:
    require_file(path, what, error)
    try:
        size = os.stat(path).st_size
        if size > MAX_YAML_BYTES:
            raise error(
                f"{what} {path} is {size:,} bytes, over the limit of {MAX_YAML_BYTES:,} for a"
                " YAML file. Is it the right file?"
            )
        return path.read_text(encoding="utf-8")
    except OSError as exc:
        raise error(f"{what} {path} cannot be read ({exc}). Check its permissions.") from exc
    except UnicodeDecodeError as exc:
        raise error(f"{what} {path} is not UTF-8 text ({exc}). Save it as UTF-8.") from exc


def read_yaml_file(path: Path, what: str, error: type[MresimError]) -> dict[str, Any]:
    """Read a YAML file holding a mapping at top level, raising ``error`` on any problem."""
    text = _read_text(path, what, error)
    try:
        data = parse_yaml(text)
    except Exception as exc:  # PyYAML's constructors raise more than YAMLError
        raise error(f"{what} {path} is not valid YAML{_yaml_problem(exc)}.") from None
    if not isinstance(data, dict):
        kind = "empty" if data is None else f"a {type(data).__name__}, not a mapping"
        raise error(f"{what} {path} is {kind}. It must hold 'key: value' pairs at top level.")
    return data


def read_yaml_mapping(path: Path) -> dict[str, Any]:
    """Read a YAML file that must hold a mapping at its top level.

    Raises:
        ScenarioError: missing or unreadable file, a YAML syntax error (with line and
            column), a document too big or whose aliases expand too far, or a top level
            that is not a mapping.
    """
    return read_yaml_file(Path(path), "Scenario file", ScenarioError)
