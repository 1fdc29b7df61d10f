"""Run logs (output edge): how every field of a snapshot is stored, one codec per field.

Each field of :class:`~mresim_phys.snapshot.Snapshot` and of its
:class:`~mresim_phys.snapshot.AgentSnapshot` s is stored in exactly one way:

* ``meta.json``, once: ``resolution``, each agent's ``name``, ``kind``, ``radius``,
  ``comm_range`` (:data:`STATIC_AGENT`) and what the explorable area was computed from
  (``sights``, ``output.logmeta``);
* ``steps.jsonl``, one JSON line per step (:class:`LineField`): ``step``, ``events``,
  ``links``, ``comm``, ``world_version``, ``meetings`` (the rendezvous accounting's
  board, ``meeting_board.py``; left out without one) (:data:`SNAPSHOT_LINE`) and per agent
  ``position``, ``heading``, ``state``, ``role``, ``goal``, ``distance``, ``parent``,
  ``base_contact``, each recorded per-robot feature's value under its key (``parts``,
  ``battery``, ``health``: the reason of a change of state, ``lost``; :class:`SpreadField`;
  logs of version 6 or older stored ``parts`` as ``broken``, ``lost`` as ``presumed_lost``
  and ``health`` as ``state_reason``) (:data:`AGENT_LINE`);
* delta chunks, as changes since the previous logged step: grids (:class:`GridField`:
  ``belief``, ``safe``, ``skeleton``, the ``truth`` when the world changed, ``rubble``
  and ``gave_way``) and point arrays (:class:`PointsField`: ``path``, ``rendezvous``,
  ``rv_candidates``, ``rv_through_walls``);
* ``movables``: what never changes in ``meta.json``, moves in the steps' lines
  (``output.logworld``);
* not at all, recomputed on replay: ``explored``, ``known_at_base``, ``alive``,
  ``lost_knowledge`` and ``failures`` (``knowledge.robustness``, from the replayed maps and
  fault states), each robot's activity in its ``health`` feature (``knowledge.health``,
  from its replayed odometer, path, state and parts).

Importing this module fails if a dataclass field has no codec here (or a codec has no
field), so a new snapshot field cannot be left out of the log by mistake.
Layout and meaning: ``docs/run-log-format.md``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import MISSING, dataclass, fields
from functools import cache, partial
from typing import Any

import numpy as np

from mresim_phys import meeting_board as meetings_board
from mresim_phys.features import FEATURES
from mresim_phys.output.logdiff import diff_into
from mresim_phys.snapshot import AgentSnapshot, CommSummary, Snapshot, read_only
from mresim_phys.types import FloatArray, IntArray

FORMAT, VERSION = "mresim-runlog", 9
READABLE = (1, 2, 3, 4, 5, 6, 7, 8, 9)  # versions it reads (how each differs: run-log-format.md)
OLD_KEYS = {"parts": "broken", "lost": "presumed_lost", "health": "state_reason"}  # version <= 6
NEW, NONE = -1, -2  # PointsField codes: the points are stored; the field is None
Parts = dict[str, list[np.ndarray]]
Chunk = dict[str, np.ndarray]


def point(value: Any) -> list[float] | None:
    """An (x, y) pair as a JSON list of full-precision floats."""
    return None if value is None else [float(value[0]), float(value[1])]


def to_point(value: Any, n: int) -> tuple[float, float] | None:
    """A JSON (x, y) pair (or null) read back."""
    return None if value is None else (float(value[0]), float(value[1]))


def plain(value: Any, n: int) -> Any:
    """A JSON value read back as it is."""
    return value


def to_int(value: Any, n: int) -> int:
    """A JSON integer read back."""
    return int(value)


def to_float(value: Any, n: int) -> float:
    """A JSON number read back as a float (bit-identical: JSON floats round-trip)."""
    return float(value)


def to_events(value: Any, n: int) -> tuple[str, ...]:
    """A JSON list of texts (events, broken parts) read back."""
    return tuple(value)


def flat_true(matrix: np.ndarray) -> list[int]:
    """Flat indices of the True entries of an (n, n) matrix."""
    return [int(i) for i in np.flatnonzero(matrix)]


def to_links(value: Any, n: int) -> np.ndarray:
    """:func:`flat_true` read back as an (n, n) bool matrix."""
    return np.isin(np.arange(n * n), value).reshape(n, n)


def to_comm(value: Any, n: int) -> CommSummary:
    """The ``comm`` object read back for ``n`` agents."""
    return CommSummary.from_json(value, n)


@dataclass(frozen=True)
class LineField:
    """A field stored as JSON: ``encode(value)``, and ``decode(json, agents)`` back.

    ``omit_none``: left out of the line when None; ``omit_empty``: left out when empty. A
    key missing from a line (a value left out, or an older log) reads back as the dataclass
    field's default.
    """

    encode: Callable[[Any], Any]
    decode: Callable[[Any, int], Any]
    omit_none: bool = False
    omit_empty: bool = False


@dataclass(frozen=True)
class SpreadField:
    """A mapping of per-robot feature values stored as one key per feature, in
    :data:`~mresim_phys.features.FEATURES` order, each by that feature's codec; a robot
    without a feature has no key for it."""

    def encode_into(self, out: dict[str, Any], values: Mapping[str, Any]) -> None:
        """Add each feature's value in ``values`` to the line ``out`` (a value encoded as
        None is left out: run health logs only a reason)."""
        for feature in FEATURES.recorded():
            value = values.get(feature.key)
            raw = None if value is None else feature.encode(value)
            if raw is not None:
                out[feature.key] = raw

    def decode_from(self, line: Mapping[str, Any]) -> dict[str, Any]:
        """The features' values in ``line`` (under their :data:`OLD_KEYS` in older logs)."""
        out = {}
        for feature in FEATURES.recorded():
            key = feature.key if feature.key in line else OLD_KEYS.get(feature.key, feature.key)
            if key in line:
                out[feature.key] = feature.decode(line[key])
        return out


SPREAD = SpreadField()
Codec = LineField | SpreadField
STATIC_AGENT = {
    "name": LineField(str, plain),
    "kind": LineField(str, plain),
    "radius": LineField(float, to_float),
    "comm_range": LineField(float, to_float),
}
AGENT_LINE: dict[str, Codec] = {
    "position": LineField(point, to_point),
    "heading": LineField(float, to_float),
    "state": LineField(str, plain),
    "role": LineField(str, plain),
    "goal": LineField(point, to_point),
    "distance": LineField(float, to_float),
    "parent": LineField(str, plain, omit_none=True),
    "base_contact": LineField(int, to_int),
    "features": SPREAD,  # each feature's value under its own key (features.py): parts, battery
}
SNAPSHOT_LINE = {
    "step": LineField(int, to_int),
    "events": LineField(list, to_events),
    "links": LineField(flat_true, to_links),
    "comm": LineField(CommSummary.to_json, to_comm),
    "world_version": LineField(int, to_int),
    # the rendezvous accounting's board, whole (version 8; a run without meetings: none)
    "meetings": LineField(meetings_board.encode, meetings_board.decode, omit_none=True),
}
# meta.json, the truth codec, per agent; then output.logworld and WORLD_GRIDS
SNAPSHOT_ELSEWHERE: tuple[str, ...] = ("resolution", "truth", "agents")
SNAPSHOT_ELSEWHERE += ("movables", "rubble", "gave_way", "terrain", "prior")  # in truth.npz
SNAPSHOT_ELSEWHERE += ("hazards",)  # in truth.npz
SNAPSHOT_ELSEWHERE += ("ground",)  # truth.npz "ground" and meta.json "ground" (version 9)
SNAPSHOT_ELSEWHERE += ("latest",)  # meta.json "beliefs"
SNAPSHOT_ELSEWHERE += ("sights",)  # meta.json "sights" (output.logmeta)
SNAPSHOT_ELSEWHERE += ("dt",)  # meta.json "dt", written when the scenario gives it
RECOMPUTED = ("explored", "known_at_base", "alive", "lost_knowledge", "failures")  # replayed


def encode_line(codecs: Mapping[str, Codec], obj: object) -> dict[str, Any]:
    """The JSON object of ``obj``'s fields named in ``codecs``."""
    out: dict[str, Any] = {}
    for name, codec in codecs.items():
        value = getattr(obj, name)
        if isinstance(codec, SpreadField):
            codec.encode_into(out, value)
        elif not (codec.omit_none and value is None) and not (codec.omit_empty and not value):
            out[name] = codec.encode(value)
    return out


def decode_line(
    codecs: Mapping[str, Codec], cls: type, line: Mapping[str, Any], n: int
) -> dict[str, Any]:
    """Keyword arguments of ``cls`` read back from ``line`` (``n`` agents); KeyError if a
    field without a default is missing."""
    defaults, out = field_defaults(cls), {}
    for name, codec in codecs.items():
        if isinstance(codec, SpreadField):
            out[name] = codec.decode_from(line)
        elif name in line:
            out[name] = codec.decode(line[name], n)
        elif name in defaults:
            out[name] = defaults[name]()
        else:
            raise KeyError(name)
    return out


def identity(value: Any) -> Any:
    """``value`` itself (a field's fixed default, as a maker)."""
    return value


@cache
def field_defaults(cls: type) -> dict[str, Callable[[], Any]]:
    """Makers of the default value of every dataclass field of ``cls`` that has one."""
    out: dict[str, Callable[[], Any]] = {}
    for f in fields(cls):
        if f.default is not MISSING:
            out[f.name] = partial(identity, f.default)
        elif f.default_factory is not MISSING:
            out[f.name] = f.default_factory
    return out


def segment(chunk: Chunk, name: str, k: int) -> slice:
    """Entry ``k`` of a chunk's variable-length ``name`` arrays (``<name>_off``)."""
    return slice(int(chunk[f"{name}_off"][k]), int(chunk[f"{name}_off"][k + 1]))


@dataclass(frozen=True)
class GridField:
    """A grid stored as its changes since the previous logged step (chunk arrays ``<name>_*``).

    ``values``: a uint8 grid; its changed cells (``_idx``, gap-encoded) and their new values
    (``_val``). Otherwise a bool grid; the cells that flipped (``_idx``). ``optional``: the
    field may be None (an ``_on`` flag per entry; a None grid leaves the last one as it was).
    """

    name: str
    values: bool
    optional: bool = False

    def arrays(self) -> dict[str, type]:
        """Its chunk arrays and their dtypes."""
        out: dict[str, type] = {f"{self.name}_idx": np.int32}
        if self.values:
            out[f"{self.name}_val"] = np.uint8
        if self.optional:
            out[f"{self.name}_on"] = np.uint8
        return out

    def write(self, copy: np.ndarray, grid: np.ndarray | None, parts: Parts) -> None:
        """Add one entry: ``grid``'s changes against ``copy`` (flat uint8, updated to match)."""
        if self.optional:
            parts[f"{self.name}_on"].append(np.array([grid is not None]))
        if grid is None:
            idx = gaps = np.zeros(0, np.int64)
        else:
            grid = np.asarray(grid, dtype=np.uint8 if self.values else bool)
            idx, gaps = diff_into(copy, grid)
        parts[f"{self.name}_idx"].append(gaps)  # gaps compress well
        if self.values:
            parts[f"{self.name}_val"].append(copy[idx])

    def read(self, state: np.ndarray, chunk: Chunk, k: int) -> IntArray | None:
        """Apply entry ``k`` to ``state`` (flat uint8); the changed cells, or None if the
        field is None there (or not in the log: an older version)."""
        flag = chunk.get(f"{self.name}_on") if self.optional else None
        if self.optional and (flag is None or not flag[k]):
            return None
        part = segment(chunk, self.name, k)
        idx = np.cumsum(chunk[f"{self.name}_idx"][part], dtype=np.int64)
        if self.values:
            state[idx] = chunk[f"{self.name}_val"][part]
        else:
            state[idx] ^= 1
        return idx

    def view(self, state: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
        """``state`` as the field's read-only grid."""
        return read_only((state if self.values else state.view(bool)).reshape(shape))


@dataclass(frozen=True)
class PointsField:
    """(k, 2) float points stored per entry as ``<name>_keep``: ``k >= 0`` keeps the last k
    points of the previous entry (a path being followed), :data:`NEW` stores them in
    ``<name>_xy``, :data:`NONE` means None (``optional`` fields)."""

    name: str
    optional: bool = False

    def arrays(self) -> dict[str, type]:
        """Its chunk arrays and their dtypes."""
        return {f"{self.name}_keep": np.int32, f"{self.name}_xy": np.float64}

    def write(self, prev: FloatArray, points: Any, parts: Parts) -> FloatArray:
        """Add one entry; return what the next entry is compared with."""
        cur = None if points is None else np.array(points, dtype=np.float64).reshape(-1, 2)
        keep = NONE if cur is None else tail_keep(prev, cur)
        parts[f"{self.name}_keep"].append(np.array([keep]))
        parts[f"{self.name}_xy"].append(
            cur if cur is not None and keep == NEW else np.zeros((0, 2))
        )
        return prev if cur is None else cur

    def read(self, prev: FloatArray, chunk: Chunk, k: int) -> tuple[FloatArray, FloatArray | None]:
        """Entry ``k`` after ``prev``: (what the next entry follows, the field's value)."""
        codes = chunk.get(f"{self.name}_keep")
        if codes is None:
            if self.optional:  # a log older than the field
                return prev, None
            raise KeyError(f"{self.name}_keep")
        keep = int(codes[k])
        if keep == NONE:
            return prev, None
        if keep == NEW:
            cur = read_only(chunk[f"{self.name}_xy"][segment(chunk, self.name, k)])
        else:
            cur = prev[len(prev) - keep :]
        return cur, cur


def tail_keep(prev: FloatArray, cur: FloatArray) -> int:
    """``len(cur)`` if ``cur`` is the tail of ``prev``, else :data:`NEW`."""
    keep = len(cur)
    same = keep <= len(prev) and np.array_equal(prev[len(prev) - keep :], cur)
    return keep if same else NEW


AGENT_GRIDS = (
    GridField("belief", values=True),
    GridField("safe", values=False),
    GridField("skeleton", values=False, optional=True),
    GridField("given_up", values=False, optional=True),  # absent from logs of version 5 or older
)
AGENT_POINTS = (
    PointsField("path"),
    PointsField("rendezvous", optional=True),
    PointsField("rv_candidates", optional=True),  # absent from logs of version 3 or older
    PointsField("rv_through_walls", optional=True),
)
TRUTH = GridField("truth", values=False)  # one entry per logged step, not per agent
WORLD_GRIDS = (  # one entry per logged step; absent from logs of version 2 or older
    GridField("rubble", values=False, optional=True),
    GridField("gave_way", values=False, optional=True),
)
ARRAYS = {
    k: v for f in (TRUTH, *WORLD_GRIDS, *AGENT_GRIDS, *AGENT_POINTS) for k, v in f.arrays().items()
}


class Track:
    """What the writer or the reader holds of one agent between logged steps."""

    def __init__(self, cells: int) -> None:
        self.grids = {g.name: np.zeros(cells, np.uint8) for g in AGENT_GRIDS}
        self.points = {p.name: read_only(np.zeros((0, 2))) for p in AGENT_POINTS}

    def write(self, agent: AgentSnapshot, parts: Parts) -> None:
        """Add ``agent``'s grid and point entries to ``parts``."""
        for grid in AGENT_GRIDS:
            grid.write(self.grids[grid.name], getattr(agent, grid.name), parts)
        for points in AGENT_POINTS:
            prev = self.points[points.name]
            self.points[points.name] = points.write(prev, getattr(agent, points.name), parts)

    def read(
        self, chunk: Chunk, k: int, shape: tuple[int, int]
    ) -> tuple[dict[str, Any], dict[str, IntArray | None]]:
        """Apply entry ``k``: the agent's grid and point fields (grids are read-only views of
        this track's arrays) and, per grid, the cells that changed."""
        values: dict[str, Any] = {}
        changed: dict[str, IntArray | None] = {}
        for grid in AGENT_GRIDS:
            state = self.grids[grid.name]
            changed[grid.name] = idx = grid.read(state, chunk, k)
            values[grid.name] = None if idx is None else grid.view(state, shape)
        for points in AGENT_POINTS:
            self.points[points.name], values[points.name] = points.read(
                self.points[points.name], chunk, k
            )
        return values, changed


def offsets(parts: list[np.ndarray]) -> np.ndarray:
    """Where each part starts in the concatenation, then the total length."""
    return np.concatenate(([0], np.cumsum([len(p) for p in parts], dtype=np.int64)))


def new_parts() -> Parts:
    """Empty per-array lists for one chunk."""
    return {name: [] for name in ARRAYS}


def chunk_arrays(parts: Parts) -> Chunk:
    """The parts gathered for a chunk as the arrays of its ``.npz`` file, with offsets
    ``<name>_off`` for every variable-length array (``_idx``, ``_xy``)."""
    arrays: Chunk = {k: np.concatenate(v).astype(ARRAYS[k]) for k, v in parts.items()}
    ragged = (k for k in parts if k.endswith(("_idx", "_xy")))
    return arrays | {f"{k.rsplit('_', 1)[0]}_off": offsets(parts[k]) for k in ragged}


def stored_fields() -> dict[type, list[str]]:
    """The fields of each snapshot class that the tables above store (or recompute)."""
    agent = [*STATIC_AGENT, *AGENT_LINE, *(f.name for f in (*AGENT_GRIDS, *AGENT_POINTS))]
    snapshot = [*SNAPSHOT_LINE, *SNAPSHOT_ELSEWHERE, *RECOMPUTED]
    return {AgentSnapshot: agent, Snapshot: snapshot}


def check_codecs() -> None:
    """Raise TypeError unless every snapshot field has exactly one codec above."""
    for cls, stored in stored_fields().items():
        names, twice = {f.name for f in fields(cls)}, {n for n in stored if stored.count(n) > 1}
        if names != set(stored) or twice:
            raise TypeError(
                f"run log: {cls.__name__} fields without a codec {sorted(names - set(stored))},"
                f" codecs without a field {sorted(set(stored) - names)}, with two codecs"
                f" {sorted(twice)}: say in mresim_phys/output/logformat.py how each field is"
                " logged (and bump VERSION)"
            )


check_codecs()
