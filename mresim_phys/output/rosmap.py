"""Maps back out (output): a robot's map, the base station's map or the truth of a run as a
ROS ``map_server`` map, so ROS users compare them with explore_lite or map_merge outputs and
reuse them in nav2.

A map is written as ``map_saver`` writes one: a PGM of trinary pixels (free 254, occupied
0, unknown 205) and a YAML with ``image``, ``resolution``, ``origin``, ``negate: 0``,
``occupied_thresh: 0.65``, ``free_thresh: 0.196`` and ``mode: trinary``. Image row 0 is
grid row 0 (the top of the map), as the ROS maps this project reads. The resolution is the
run's (metres per cell; 1.0 when the scenario gave none: cells), the origin that of the
scenario's ROS map (the lower-left corner of the lower-left pixel; (0, 0, 0) for an image
or text map). :func:`read_ros_belief` reads such a map back, cell for cell.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import yaml
from PIL import Image

from mresim_phys.errors import MresimError
from mresim_phys.output.runlog import RunLog
from mresim_phys.scenario.readers import read_yaml_mapping
from mresim_phys.types import FREE, OCCUPIED, UNKNOWN, BeliefGrid, BoolGrid

FREE_PIXEL, OCCUPIED_PIXEL, UNKNOWN_PIXEL = 254, 0, 205  # map_saver's trinary values
OCCUPIED_THRESH, FREE_THRESH = 0.65, 0.196
TRUTH, BASE = "truth", "base"


def write_ros_map(
    grid: BeliefGrid, stem: Path, resolution: float, origin: tuple[float, float, float]
) -> tuple[Path, Path]:
    """Write ``grid`` (FREE / OCCUPIED / UNKNOWN codes) as ``stem``.pgm and ``stem``.yaml."""
    pixels = np.full(grid.shape, UNKNOWN_PIXEL, dtype=np.uint8)
    pixels[grid == FREE] = FREE_PIXEL
    pixels[grid == OCCUPIED] = OCCUPIED_PIXEL
    stem.parent.mkdir(parents=True, exist_ok=True)
    pgm, meta = stem.with_suffix(".pgm"), stem.with_suffix(".yaml")
    Image.fromarray(pixels, mode="L").save(pgm)
    data = {
        "image": pgm.name, "resolution": float(resolution),
        "origin": [float(v) for v in origin], "negate": 0,
        "occupied_thresh": OCCUPIED_THRESH, "free_thresh": FREE_THRESH, "mode": "trinary",
    }  # fmt: skip
    meta.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return meta, pgm


def read_ros_belief(yaml_path: Path) -> BeliefGrid:
    """A trinary ROS map read back as FREE / OCCUPIED / UNKNOWN codes (p = (255 - value) /
    255: above ``occupied_thresh`` occupied, below ``free_thresh`` free, else unknown)."""
    meta = read_yaml_mapping(yaml_path)
    with Image.open(yaml_path.parent / str(meta["image"])) as img:
        value = np.asarray(img.convert("L"), dtype=np.float64)
    p = (255.0 - value) / 255.0
    if meta.get("negate", 0):
        p = 1.0 - p
    out = np.full(value.shape, UNKNOWN, dtype=np.uint8)
    out[p > float(meta.get("occupied_thresh", OCCUPIED_THRESH))] = OCCUPIED
    out[p < float(meta.get("free_thresh", FREE_THRESH))] = FREE
    return out


def truth_codes(occupied: BoolGrid) -> BeliefGrid:
    """The truth as map codes: every cell known."""
    codes: BeliefGrid = np.where(occupied, OCCUPIED, FREE).astype(np.uint8)
    return codes


def map_at(log: RunLog, which: str, step: int | None) -> tuple[BeliefGrid, int]:
    """(grid, step) of ``which`` (a robot's name, ``base`` or ``truth``) at logged step
    ``step`` (None: the last)."""
    names = [*log.names, TRUTH]
    if which not in names:
        robots = ", ".join(log.robot_names)
        raise MresimError(
            f"{log.log_dir}: no map {which!r} in this run; give a robot ({robots}),"
            f" {BASE!r} or {TRUTH!r}"
        )
    last = log.steps - 1
    wanted = last if step is None else step
    if not 0 <= wanted <= last:
        raise MresimError(f"{log.log_dir}: step {step} is not logged (steps 0 to {last})")
    for snap in log.snapshots():
        if snap.step == wanted:
            if which == TRUTH:
                return truth_codes(snap.truth), wanted
            agent = next(a for a in snap.agents if a.name == which)
            return np.array(agent.belief, dtype=np.uint8), wanted
    raise MresimError(f"{log.log_dir}: step {wanted} was not found in the log")


def frame_of(run_dir: Path, log: RunLog) -> tuple[float, tuple[float, float, float]]:
    """(resolution, origin) of the run's map (module docstring)."""
    resolution = float(log.meta.get("resolution") or 1.0)
    origin: tuple[float, float, float] = (0.0, 0.0, 0.0)
    scenario = run_dir / "scenario.yaml"
    ros = None
    if scenario.is_file():
        ros = (read_yaml_mapping(scenario).get("map") or {}).get("ros")
    if ros:
        given: Any = read_yaml_mapping(Path(ros)).get("origin") or [0.0, 0.0, 0.0]
        origin = (float(given[0]), float(given[1]), float(given[2]) if len(given) > 2 else 0.0)
    return resolution, origin


def export_map(run_dir: Path, which: str, step: int | None, out: Path | None) -> tuple[Path, Path]:
    """Write ``which``'s map at ``step`` of the run in ``run_dir`` as a ROS map in ``out``
    (default ``run_dir/maps``), named ``<which>-step<step>``; (yaml, pgm)."""
    log = RunLog.open(run_dir / "log")
    grid, at = map_at(log, which, step)
    resolution, origin = frame_of(run_dir, log)
    folder = out if out is not None else run_dir / "maps"
    return write_ros_map(grid, folder / f"{which}-step{at:05d}", resolution, origin)


def export_map_command(args: Any) -> int:
    """``mresim export-map``: write a map of a run as a ROS map_server map."""
    yaml_path, pgm = export_map(args.run_dir, args.map, args.step, args.out)
    print(f"wrote {yaml_path} and {pgm}")
    return 0
