"""Run selection (sweeps, input): ``--video-for 'seed < 2 and strategy == "frontier"'``.

A small, safe expression language over a run's values: comparisons (``<``, ``<=``,
``==``, ``!=``, ``>``, ``>=``, ``in``, ``not in``), ``and``, ``or``, ``not``, numbers,
strings, ``None``/``null``, lists, and the names ``seed``, ``arm``, ``scenario`` and each
axis by its path with dots as underscores (``team_strategy``) or by its last part
(``strategy``, ``count``, ``failures``). Nothing else is evaluated.
"""

from __future__ import annotations

import ast
import operator
from collections.abc import Callable, Mapping
from typing import Any

from mresim_phys.errors import MresimError

COMPARE: dict[type[ast.cmpop], Callable[[Any, Any], bool]] = {
    ast.Lt: operator.lt,
    ast.LtE: operator.le,
    ast.Eq: operator.eq,
    ast.NotEq: operator.ne,
    ast.Gt: operator.gt,
    ast.GtE: operator.ge,
    ast.In: lambda a, b: a in b,
    ast.NotIn: lambda a, b: a not in b,
}


def run_names(seed: int, arm: int, scenario: str, values: Mapping[str, Any]) -> dict[str, Any]:
    """The names an expression may use for one run."""
    names: dict[str, Any] = {"null": None}
    for path, value in values.items():
        names.setdefault(path.rsplit(".", 1)[-1], value)
        names[path.replace(".", "_")] = value
    return names | {"seed": seed, "arm": arm, "scenario": scenario}


def parse_selection(text: str) -> ast.expr:
    """``text`` parsed; MresimError if it is no expression of the allowed kind."""
    try:
        tree = ast.parse(text, mode="eval").body
    except SyntaxError as exc:
        raise MresimError(f"--video-for {text!r}: not an expression ({exc.msg}).") from None
    except (ValueError, RecursionError, MemoryError) as exc:  # null bytes; nested too deep
        why = str(exc) or "nested too deep"
        raise MresimError(f"--video-for {text!r}: not an expression ({why}).") from None
    allowed = (
        ast.Compare,
        ast.BoolOp,
        ast.UnaryOp,
        ast.Name,
        ast.Constant,
        ast.List,
        ast.Tuple,
        ast.Load,
        ast.And,
        ast.Or,
        ast.Not,
        ast.USub,
        *COMPARE,
    )
    for node in ast.walk(tree):
        if not isinstance(node, allowed):
            raise MresimError(
                f"--video-for {text!r}: {type(node).__name__} is not allowed; use comparisons"
                " of seed, arm, scenario and the axes joined by and / or, e.g. 'seed < 2'."
            )
    return tree


def evaluate(node: ast.expr, names: Mapping[str, Any], text: str) -> Any:
    """The value of a parsed selection for one run's ``names``."""
    if isinstance(node, ast.Constant):
        return node.value
    if isinstance(node, ast.Name):
        if node.id not in names:
            known = ", ".join(sorted(k for k in names if k != "null"))
            raise MresimError(f"--video-for {text!r}: unknown name {node.id!r}; use {known}.")
        return names[node.id]
    if isinstance(node, (ast.List, ast.Tuple)):
        return [evaluate(e, names, text) for e in node.elts]
    if isinstance(node, ast.UnaryOp):
        value = evaluate(node.operand, names, text)
        return (not value) if isinstance(node.op, ast.Not) else negative(value, node, text)
    if isinstance(node, ast.BoolOp):
        values = [bool(evaluate(v, names, text)) for v in node.values]
        return all(values) if isinstance(node.op, ast.And) else any(values)
    assert isinstance(node, ast.Compare)
    left = evaluate(node.left, names, text)
    for op, right_node in zip(node.ops, node.comparators, strict=True):
        right = evaluate(right_node, names, text)
        try:
            if not COMPARE[type(op)](left, right):
                return False
        except TypeError:
            return False
        left = right
    return True


def negative(value: Any, node: ast.UnaryOp, text: str) -> Any:
    """``-value``; MresimError unless ``value`` is a number."""
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return -value
    raise MresimError(
        f"--video-for {text!r}: {ast.unparse(node)!r} puts a minus before {value!r}, which is"
        " not a number (a minus applies to numbers only, e.g. 'seed > -1'); compare string"
        " axes with == or in, e.g. \"strategy == 'frontier'\"."
    )


def selector(text: str | None) -> Callable[[Mapping[str, Any]], bool]:
    """A predicate over a run's names (always False without ``text``)."""
    if text is None:
        return lambda names: False
    tree = parse_selection(text)
    return lambda names: bool(evaluate(tree, names, text))
