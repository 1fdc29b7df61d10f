"""Instance sets (phase 0, input data): many procedural maps of a kind, split for learning.

``mresim make-set SET.yaml --out DIR`` reads a set file::

    name: small-buildings
    instances:
      - {kind: building, size: [300, 200], seeds: 20}                 # seeds 0..19
      - {kind: blueprint, size: [240, 160], params: {shape: loop+room}, seeds: [0]}
    robots: 4          # starts placed on every map
    radius: 2.0        # the body they fit
    split: {test: 0.2, seed: 0}   # the share held out for testing, drawn from its seed

and draws every instance as ``mresim make-map`` does into ``DIR/<id>/`` (``map.png``,
``map.yaml``, ``scenario.yaml``), then writes ``DIR/set.yaml``: the set's name, the
generator's version, and per instance its id, kind, seed, size, parameters, grid SHA-256
and split (``train`` or ``test``). The split is a seeded permutation of the instances (the
stream ``set-split`` of ``split.seed``): the same set file gives the same split, and at
least one instance on each side when there are two or more.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Literal

import numpy as np
import yaml
from pydantic import Field, ValidationError, model_validator

from mresim_phys.errors import MresimError
from mresim_phys.mapgen.errors import describe
from mresim_phys.mapgen.generate import GENERATOR, GeneratedMap, generate, write_map
from mresim_phys.mapgen.params import MAX_SIZE, MIN_SIZE, Kind, MapRequest
from mresim_phys.mapgen.place import base_and_starts
from mresim_phys.rng import Streams
from mresim_phys.scenario.readers import load_map
from mresim_phys.strict import Strict

MAX_INSTANCES = 10_000


class InstanceSpec(Strict):
    """Maps of one kind, size and parameters, one per seed; or (``kind: file``) a map
    file, its seeds placing the base and the starts."""

    kind: Kind | Literal["file"]
    size: tuple[int, int] | None = Field(None, description="[width, height] in cells.")
    map: str | None = Field(
        None, description="kind file: a map file (png, pgm + yaml, txt), relative to the set."
    )
    seeds: int | list[int] = Field(
        description="How many seeds (0, 1, ...) or which ones.", union_mode="left_to_right"
    )
    params: dict[str, Any] = Field(default_factory=dict, description="The kind's parameters.")

    @model_validator(mode="after")
    def _source(self) -> InstanceSpec:
        if (self.kind == "file") != (self.map is not None):
            raise ValueError("give 'map: FILE' with kind file, and only with it")
        if self.kind != "file" and self.size is None:
            raise ValueError(f"a {self.kind} needs its size: [width, height]")
        return self

    def seed_list(self) -> list[int]:
        """The seeds this entry draws."""
        return list(range(self.seeds)) if isinstance(self.seeds, int) else list(self.seeds)


class SplitSpec(Strict):
    """How much of the set is held out for testing."""

    test: float = Field(0.2, ge=0, lt=1, description="Share of the instances held out.")
    seed: int = Field(0, ge=0, le=2**63 - 1, description="Seeds the permutation.")


class SetSpec(Strict):
    """A set file (module docstring)."""

    name: str = Field(min_length=1, max_length=64)
    instances: list[InstanceSpec] = Field(min_length=1)
    robots: int = Field(4, ge=1, le=256)
    radius: float = Field(2.0, gt=0, le=50)
    split: SplitSpec = Field(default_factory=SplitSpec)

    def requests(self) -> list[MapRequest]:
        """One map request per procedural instance, in the file's order (ValueError: too
        many, or a size out of range, naming the entry)."""
        out = []
        for i, entry in enumerate(self.instances):
            if entry.size is None:
                continue
            width, height = entry.size
            if not (MIN_SIZE <= width <= MAX_SIZE and MIN_SIZE <= height <= MAX_SIZE):
                raise ValueError(
                    f"instances[{i}].size: each side is {MIN_SIZE} to {MAX_SIZE} cells"
                )
            for seed in entry.seed_list():
                out.append(MapRequest(
                    kind=entry.kind, seed=seed, width=width, height=height,
                    robots=self.robots, radius=self.radius, params=entry.params,
                ))  # fmt: skip
        if len(out) > MAX_INSTANCES:
            raise ValueError(f"instances: {len(out)} maps, more than {MAX_INSTANCES}")
        return out


def from_file(path: Path, seed: int, spec: SetSpec, owner: int) -> GeneratedMap:
    """A map file as an instance: its grid as read, the base and starts drawn from
    ``seed`` (ValueError naming the entry when it cannot be read or has no room)."""
    try:
        loaded = load_map(path.resolve())
    except MresimError as exc:
        raise ValueError(f"instances[{owner}].map: {exc}") from None
    rows, cols = loaded.occupied.shape
    request = MapRequest.model_construct(
        kind="file", seed=seed, width=cols, height=rows, robots=spec.robots,
        radius=spec.radius, params={"map": str(path)},
    )  # fmt: skip
    occupied = np.asarray(loaded.occupied, dtype=bool)
    try:
        base, starts = base_and_starts(
            occupied, spec.radius, spec.robots, Streams(seed).get("map-places")
        )
    except ValueError as exc:
        raise ValueError(f"instances[{owner}] ({path.name}): {exc}") from None
    return GeneratedMap(request, FileParams(map=str(path)), occupied, base, starts)


class FileParams(Strict):
    """A map file's 'parameters': where it was read from."""

    map: str


def instance_id(request: MapRequest, entry: int) -> str:
    """A folder name for an instance: entry, kind and seed."""
    return f"{entry:02d}-{request.kind}-s{request.seed}"


def split_of(count: int, spec: SplitSpec) -> list[str]:
    """``train`` or ``test`` for each of ``count`` instances (module docstring)."""
    held = round(spec.test * count)
    if count >= 2 and spec.test > 0:
        held = min(max(held, 1), count - 1)
    order = Streams(spec.seed).get("set-split").permutation(count)
    sides = np.array(["train"] * count, dtype=object)
    sides[order[:held]] = "test"
    return [str(s) for s in sides]


def make_set(spec: SetSpec, folder: Path, source: Path | None = None) -> dict[str, Any]:
    """Draw and write every instance of ``spec`` into ``folder`` and its index, set.yaml
    (ValueError naming the entry and parameter of an instance that cannot be drawn; map
    files are relative to ``source``'s folder)."""
    requests = iter(spec.requests())
    made = []
    for owner, entry in enumerate(spec.instances):
        for seed in entry.seed_list():
            if entry.map is not None:
                base = Path(".") if source is None else source.parent
                made.append((owner, from_file(base / entry.map, seed, spec, owner)))
                continue
            request = next(requests)
            try:
                made.append((owner, generate(request)))
            except ValidationError as exc:
                raise ValueError(f"instances[{owner}].params.{describe(exc)}") from None
            except ValueError as exc:
                raise ValueError(f"instances[{owner}] (seed {request.seed}): {exc}") from None
    sides = split_of(len(made), spec.split)
    index: dict[str, Any] = {"name": spec.name, "generator": GENERATOR, "instances": []}
    for (owner, m), side in zip(made, sides, strict=True):
        name = instance_id(m.request, owner)
        write_map(m, folder / name, name)
        r = m.request
        index["instances"].append({
            "id": name, "kind": r.kind, "seed": r.seed, "size": [r.width, r.height],
            "params": m.params.model_dump(), "grid_sha256": m.sha256, "split": side,
        })  # fmt: skip
    index["train"] = sides.count("train")
    index["test"] = sides.count("test")
    (folder / "set.yaml").write_text(yaml.safe_dump(index, sort_keys=False), encoding="utf-8")
    return index
