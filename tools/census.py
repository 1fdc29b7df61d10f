"""Census of the package's shape: modules, their sizes, function body lengths.

``python tools/census.py`` prints the number of modules, the largest ones, and the
median, p99 and longest function body (lines from the first statement after the
docstring to the end), the figures the architecture notes quote.
"""

from __future__ import annotations

import ast
import statistics
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "mresim_phys"


def body_lines(node: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    """Lines of a function's body, its docstring left out."""
    body = node.body
    if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
        body = body[1:]
    if not body:
        return 0
    return (body[-1].end_lineno or body[-1].lineno) - body[0].lineno + 1


def functions(path: Path) -> list[tuple[str, int]]:
    """(qualified place, body lines) of every function in ``path``."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    found = []
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            found.append((f"{path.relative_to(ROOT)}:{node.name}", body_lines(node)))
    return found


def main() -> int:
    """Print the census."""
    modules = sorted(PACKAGE.rglob("*.py"))
    sizes = sorted(((len(p.read_text().splitlines()), p) for p in modules), reverse=True)
    bodies = [f for p in modules for f in functions(p)]
    lengths = sorted(n for _, n in bodies)
    longest = max(bodies, key=lambda f: f[1])
    p99 = lengths[min(len(lengths) - 1, int(0.99 * len(lengths)))]
    print(f"modules: {len(modules)}; over 400 lines: {sum(n > 400 for n, _ in sizes)}")
    print("largest: " + ", ".join(f"{p.relative_to(PACKAGE)} {n}" for n, p in sizes[:5]))
    print(f"functions: {len(lengths)}; body median {statistics.median(lengths):g}, p99 {p99}")
    print(f"longest: {longest[0]} ({longest[1]} lines)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
