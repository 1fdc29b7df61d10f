"""Scenario schema, the run's settings (phase 0, input): ``stop``, ``simulation``, ``render``
and ``metrics`` as pydantic models (pure: pydantic and the standard library).

Part of the YAML contract of ``scenario/schema.py``, which holds the :class:`Scenario`.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, model_validator

from mresim_phys.strict import Strict

MAX_THREADS = 1024  # simulation.threads: more than any machine's cores, fewer than a typo's


class StopSpec(Strict):
    """Optional early stop rules (the run also stops at ``steps``)."""

    explored: float | None = Field(None, gt=0, le=1, description="Team-known fraction.")
    known_at_base: float | None = Field(None, gt=0, le=1, description="Base-known fraction.")
    all_done: bool = Field(True, description="Stop when every robot is done or failed.")
    stalled_for: int | None = Field(
        300,
        ge=1,
        le=1_000_000,
        description=(
            "Stop when neither explored nor known at base has gained stalled_gain in this"
            " many steps and no robot was done for the first time in them (it sets out to"
            " bring its map home; stop reason 'stalled'); null = never."
        ),
    )
    stalled_gain: float = Field(
        0.001,
        ge=0,
        le=1,
        description="Smallest gain (fraction of the free area) that counts as progress.",
    )


class StartJitterSpec(Strict):
    """Per-robot random offsets of the declared starts, drawn from the seed."""

    position: float = Field(
        0.0, ge=0, le=1000, description="Largest shift of a start (cells, uniform in a disk)."
    )
    heading_deg: float = Field(
        0.0, ge=0, le=180, description="Largest turn of a start heading (degrees, uniform, +-)."
    )


class SimulationSpec(Strict):
    """How the cycle runs."""

    scan: Literal["point", "step"] = Field(
        "point", description="Scan after every path point (as the original) or once per step."
    )
    robots_block: bool = Field(False, description="Robots block each other's rays and motion.")
    multi_hop: bool = Field(
        True, description="Information flows along chains of linked agents within a step."
    )
    presume_lost_after: int = Field(
        200,
        ge=1,
        description="Steps without news after which a strategy sees a teammate as presumed lost.",
    )
    vary_with_seed: bool = Field(
        True,
        description=(
            "The seed varies the run: initial random-walk steps, auction tie-breaks and"
            " start_jitter; false makes every seed give the same run (noise and dropouts"
            " you turn on still draw from the seed)."
        ),
    )
    start_jitter: StartJitterSpec = Field(
        default_factory=StartJitterSpec,
        description="Random shifts of the robots' starts (position and heading) per seed.",
    )
    belief: Literal["auto", "latest", "grow"] = Field(
        "auto",
        description=(
            "How robots' maps change: 'latest' (each cell holds its latest observation: a"
            " scan overwrites what it sees, an exchange keeps the newer observation, ties go"
            " to the obstacle), 'grow' (known cells only grow: unknown < free < obstacle, as"
            " the original), or 'auto': latest when the world can change (obstacles, doors,"
            " debris, collapse or cells events), grow otherwise."
        ),
    )
    paired: bool = Field(
        False,
        description=(
            "Also run the same scenario and seed with every fault switched off (no fail"
            " events) as a baseline, and write robustness.json (as `mresim run --paired`)."
        ),
    )
    threads: Annotated[int, Field(ge=1, le=MAX_THREADS)] | Literal["auto"] = Field(
        1,
        description=(
            "Threads (a number, or auto = one per core) for the robots' replans, moves,"
            " scans and map updates within a step; 1 = one robot after another. The results"
            " are the same."
        ),
    )


class RenderSpec(Strict):
    """What a run leaves besides its metrics: video, pictures, run log, plots."""

    video: bool | str = Field(
        False, description="Write a video: true = videos/<name>-seed<seed>.mp4, or a path."
    )
    fps: float = Field(20.0, gt=0, le=240, description="Video frames per second.")
    every: int = Field(1, ge=1, description="One video frame every this many steps.")
    layers: str = Field(
        "default", description="Layers to draw, e.g. 'default', 'all', 'default,B:free_space'."
    )
    scale: float = Field(1.0, gt=0, le=8, description="Frame scale (2 = twice the map size).")
    min_side: int = Field(
        640,
        ge=0,
        le=4096,
        description=(
            "Frames of a small map are drawn larger, by the smallest whole factor times"
            " scale that makes their longer side at least this many pixels, so the header"
            " and legend fit (a 160x120 map: 640x480); 0: exactly scale."
        ),
    )
    codec: Literal["h264", "mp4v", "vp8", "mjpg"] | None = Field(
        None,
        description=(
            "Video codec (default from the extension: .mp4 H.264, which browsers play;"
            " .webm VP8; .avi MJPG). mp4v: OpenCV's MPEG-4, which browsers do not play."
        ),
    )
    snapshots: list[Annotated[int, Field(ge=0)]] = Field(
        default_factory=list,
        description="Steps at which to write PNG frames (0 .. steps).",
    )
    final_png: bool = Field(True, description="Write final.png of the last step.")
    log: bool = Field(True, description="Write the run log (for replay without re-running).")
    plots: bool = Field(True, description="Write plots at the end (needs the plot extra).")


class BudgetSpec(Strict):
    """Success within a budget: a fraction reached within a number of steps."""

    explored: float | None = Field(None, gt=0, le=1, description="The explored fraction to reach.")
    known_at_base: float | None = Field(
        None, gt=0, le=1, description="The fraction known at the base to reach."
    )
    within: int = Field(ge=1, description="Steps the run may take to reach it.")

    @model_validator(mode="after")
    def _one_goal(self) -> BudgetSpec:
        if (self.explored is None) == (self.known_at_base is None):
            raise ValueError("give exactly one of 'explored' or 'known_at_base' to reach")
        return self


class MetricsSpec(Strict):
    """What ``metrics.csv`` and ``summary.json`` hold beyond their defaults."""

    columns: list[str] = Field(
        default_factory=list,
        description="Optional metric columns written after the default ones, in this order:"
        " a column's name (robots_done, base_links, robot_base_link, robot_battery, or one a"
        " package registers) or package.module:Class; see docs/metric-columns.md.",
    )
    levels: list[Annotated[float, Field(gt=0, le=1)]] = Field(
        default_factory=list,
        max_length=20,
        description="More coverage levels for steps_to_explored and steps_to_known_at_base"
        " (beside 0.5, 0.9, 0.95), e.g. [0.85, 0.99].",
    )
    budget: BudgetSpec | None = Field(
        None,
        description="Success within a budget: {explored or known_at_base: level, within:"
        " steps}; summary.json's success (true, false).",
    )
    team: bool = Field(
        False,
        description="Count each robot's discoveries: the columns overlap, workload_cv,"
        " discovered_<robot>, longest_path and connected_to_base, and summary.json's team"
        " object.",
    )
