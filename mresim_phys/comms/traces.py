"""Recorded link quality (phase 6, links): a trace of link states, or a table of measured
loss against wall count and distance.

**Trace** (``trace: links.csv``): a CSV with the header ``step,a,b`` and any of ``up``,
``loss``, ``capacity``. A row sets the pair ``a``-``b`` (robot names or ``base``) from its
step on, until the pair's next row: ``up`` 1 links the pair whatever the model says, 0
cuts it, blank leaves it to the model; ``loss`` is a probability per step of losing the
link; ``capacity`` bytes per step (blank: the channel's). Rows are in step order. A
failed or silenced agent stays silent whatever the trace says.

**Loss table** (``loss_table:``): rows ``walls, distance, loss``. A linked pair whose
straight line crosses ``W`` walls at distance ``d`` loses its link for the step with the
loss interpolated linearly in distance among the rows of the largest wall count <= ``W``
(held constant beyond the first and last distance). The table must have rows for 0 walls.

Loss draws come from the channel's ``trace-<channel>`` and ``loss-<channel>`` streams, one
per pair and step for every pair. Parsing errors are :class:`TraceError` with the line.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mresim_phys.types import FloatArray

MAX_FILE = 64 * 1024 * 1024  # bytes: a trace beyond this is not a trace
FIELDS = ("up", "loss", "capacity")


class TraceError(ValueError):
    """A trace or loss table that cannot be used; the message names the line."""


@dataclass(frozen=True)
class TraceRow:
    """One row: pair (i, j) from ``step`` on. ``up`` -1 (model), 0 or 1; ``loss`` NaN when
    blank; ``capacity`` -1 when blank."""

    step: int
    i: int
    j: int
    up: int
    loss: float
    capacity: int


def read_text(path: Path) -> str:
    """The file's text; a TraceError if it is missing, too large or not UTF-8."""
    try:
        if path.stat().st_size > MAX_FILE:
            raise TraceError(f"{path} is larger than {MAX_FILE // 2**20} MiB")
        return path.read_text(encoding="utf-8-sig")  # a spreadsheet's byte-order mark too
    except (OSError, UnicodeDecodeError) as exc:
        raise TraceError(f"{path} cannot be read ({exc})") from None


def csv_rows(text: str) -> tuple[list[str], list[tuple[int, dict[str, str]]]]:
    """A CSV's header and its rows (line number, values by column, stripped); a file the
    csv module refuses (a field beyond its limit, a stray NUL) is a TraceError."""
    try:
        reader = csv.DictReader(io.StringIO(text))
        header = [h.strip() for h in reader.fieldnames or []]
        rows = [
            (line, {k.strip(): (v or "").strip() for k, v in raw.items() if k is not None})
            for line, raw in enumerate(reader, start=2)
        ]
    except csv.Error as exc:
        raise TraceError(f"it is not a CSV file the csv module can read ({exc})") from None
    return header, rows


def parse_trace(text: str, names: Sequence[str]) -> list[TraceRow]:
    """The rows of a trace CSV whose agents are ``names`` (index 0 the base)."""
    header, lines = csv_rows(text)
    missing = [k for k in ("step", "a", "b") if k not in header]
    unknown = [k for k in header if k not in ("step", "a", "b", *FIELDS)]
    if missing or unknown or not any(k in header for k in FIELDS):
        raise TraceError(
            f"the header is {header}; it needs step, a, b and at least one of up, loss,"
            f" capacity, and nothing else{f' (unknown: {unknown})' if unknown else ''}"
        )
    rows, last = [], 0
    for line, values in lines:
        row = _row(values, names, line)
        if row.step < last:
            raise TraceError(f"line {line}: step {row.step} comes after step {last}; sort by step")
        rows.append(row)
        last = row.step
    return rows


def _row(values: dict[str, str], names: Sequence[str], line: int) -> TraceRow:
    """One trace row, checked."""
    step = _number(values.get("step", ""), int, line, "step", 0, 10**9)
    i, j = (_agent(values.get(k, ""), names, line, k) for k in ("a", "b"))
    if i == j:
        raise TraceError(f"line {line}: a and b are both {names[i]!r}; a link joins two agents")
    up = values.get("up", "")
    if up not in ("", "0", "1"):
        raise TraceError(f"line {line}: up is {up!r}; give 1, 0 or leave it blank")
    loss = values.get("loss", "")
    capacity = values.get("capacity", "")
    return TraceRow(
        int(step),
        min(i, j),
        max(i, j),
        int(up) if up else -1,
        float(_number(loss, float, line, "loss", 0, 1)) if loss else math.nan,
        int(_number(capacity, int, line, "capacity", 0, 10**9)) if capacity else -1,
    )


def _agent(name: str, names: Sequence[str], line: int, column: str) -> int:
    """The index of agent ``name``."""
    if name not in names:
        raise TraceError(f"line {line}: {column} is {name!r}, not an agent; they are {list(names)}")
    return list(names).index(name)


def _number(text: str, kind: type, line: int, column: str, low: float, high: float) -> float:
    """``text`` as a number of ``kind`` within [low, high]."""
    try:
        value = kind(text)
    except ValueError:
        raise TraceError(f"line {line}: {column} is {text!r}, not a number") from None
    if not (low <= value <= high) or (kind is float and not math.isfinite(value)):
        raise TraceError(f"line {line}: {column} is {text}; give a value from {low} to {high}")
    return float(value)


@dataclass
class LinkTrace:
    """A trace replayed step by step: each pair's current override among ``n`` agents."""

    rows: list[TraceRow]
    n: int
    rng: np.random.Generator
    up: np.ndarray = field(init=False)
    loss: FloatArray = field(init=False)
    capacity: np.ndarray = field(init=False)
    next_row: int = 0

    def __post_init__(self) -> None:
        self.up = np.full((self.n, self.n), -1, dtype=np.int8)
        self.loss = np.full((self.n, self.n), np.nan)
        self.capacity = np.full((self.n, self.n), -1, dtype=np.int64)

    def advance(self, step: int) -> None:
        """Apply every row whose step has come."""
        while self.next_row < len(self.rows) and self.rows[self.next_row].step <= step:
            r = self.rows[self.next_row]
            for a, b in ((r.i, r.j), (r.j, r.i)):
                self.up[a, b], self.loss[a, b], self.capacity[a, b] = r.up, r.loss, r.capacity
            self.next_row += 1

    def apply(self, links: np.ndarray, speaking: np.ndarray, step: int) -> np.ndarray:
        """``links`` with this step's overrides and trace losses (among ``speaking`` agents)."""
        self.advance(step)
        forced = np.where(self.up == 1, True, np.where(self.up == 0, False, links))
        rows, cols = np.triu_indices(self.n, k=1)
        draw = self.rng.random(len(rows)) < np.nan_to_num(self.loss[rows, cols], nan=0.0)
        lost = np.zeros_like(links)
        lost[rows[draw], cols[draw]] = lost[cols[draw], rows[draw]] = True
        out: np.ndarray = forced & ~lost & np.outer(speaking, speaking)
        np.fill_diagonal(out, False)
        return out

    @property
    def has_capacity(self) -> bool:
        """Whether any row sets a capacity."""
        return any(r.capacity >= 0 for r in self.rows)


def parse_loss_table(text: str) -> list[tuple[int, float, float]]:
    """The rows of a loss-table CSV (header ``walls,distance,loss``)."""
    header, lines = csv_rows(text)
    if sorted(header) != ["distance", "loss", "walls"]:
        raise TraceError(f"the header is {header}; a loss table has walls, distance, loss")
    return [
        (
            int(_number(values["walls"], int, line, "walls", 0, 1000)),
            _number(values["distance"], float, line, "distance", 0, 1e5),
            _number(values["loss"], float, line, "loss", 0, 1),
        )
        for line, values in lines
    ]


class LossTable:
    """Loss probability against wall count and distance, interpolated (module docstring)."""

    def __init__(self, rows: Sequence[tuple[int, float, float]], rng: np.random.Generator):
        check_loss_table(rows)
        self.rng = rng
        self.walls = sorted({w for w, _, _ in rows})
        self.curves = {}
        for w in self.walls:
            points = sorted((d, p) for k, d, p in rows if k == w)
            self.curves[w] = (np.array([d for d, _ in points]), np.array([p for _, p in points]))

    def loss(self, walls: np.ndarray, distance: FloatArray) -> FloatArray:
        """The loss probability of pairs crossing ``walls`` walls at ``distance``."""
        out = np.zeros(len(distance))
        keys = np.array(self.walls)
        group = keys[np.searchsorted(keys, walls, side="right") - 1]
        for w in np.unique(group).tolist():
            at = group == w
            xs, ps = self.curves[w]
            out[at] = np.interp(distance[at], xs, ps)
        return out


def check_loss_table(rows: Sequence[tuple[int, float, float]]) -> None:
    """A TraceError unless the table has rows for 0 walls and no distance twice per count."""
    if not rows or min(w for w, _, _ in rows) != 0:
        raise TraceError("a loss table needs at least one row for 0 walls")
    seen: set[tuple[int, float]] = set()
    for w, d, _ in rows:
        if (w, d) in seen:
            raise TraceError(f"the loss table gives walls {w}, distance {d} twice")
        seen.add((w, d))


def loss_rows(table: str | list[tuple[int, float, float]]) -> list[tuple[int, float, float]]:
    """A loss table's rows: given inline, or read from its CSV file (an absolute path once
    the scenario is loaded)."""
    if isinstance(table, str):
        return parse_loss_table(read_text(Path(table)))
    return [(int(w), float(d), float(p)) for w, d, p in table]


def trace_rows(path: str, names: Sequence[str]) -> list[TraceRow]:
    """The rows of the trace file at ``path`` among agents ``names`` (index 0 the base)."""
    return parse_trace(read_text(Path(path)), names)
